//! The safety layer, applied last to every force before it reaches a device: engagement, watchdog,
//! clamps, force-rate limit, and NaN/inf removal (the habits of CHAI3D, OpenHaptics and Force Dimension).
//!
//! You need this module whenever forces go to real hardware; the order inside [`SafetyLayer::apply`] is:
//! 1. non-finite requests become zero (counted);
//! 2. **engagement**: output stays zero until the request has stayed below `engage_threshold_n` for more
//!    than `engage_ticks` ticks, then the gain ramps from 0 to 1 over `ramp_in_s`;
//! 3. **watchdog**: when the contact data is older than `watchdog_timeout_s`, the gain ramps to zero over
//!    `ramp_out_s`; fresh data ramps it back over `ramp_in_s`;
//! 4. **clamp** to `max_force_n` / `max_torque_nm`;
//! 5. **rate limit**: the output moves towards the target by at most `max_force_rate_n_per_s · dt` (and
//!    the torque likewise), so no tick kicks.

use glam::Vec3;
use haptic_common::ForceTorque;

use crate::error::{Result, non_negative, positive};

/// Limits and timings of the safety layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SafetyConfig {
    /// Largest force magnitude ever output, N (set to the device's peak force).
    pub max_force_n: f32,
    /// Largest torque magnitude ever output, N·m (0 for 3-DOF devices).
    pub max_torque_nm: f32,
    /// Largest change of force per second, N/s (default 500: 0.5 N per 1 ms tick).
    pub max_force_rate_n_per_s: f32,
    /// Largest change of torque per second, N·m/s (default 10).
    pub max_torque_rate_nm_per_s: f32,
    /// Forces engage only after the request stays below this, N (default 0.2).
    pub engage_threshold_n: f32,
    /// ... for more than this many ticks (default 3).
    pub engage_ticks: u32,
    /// Ramp-in time after engagement or after the watchdog recovers, s (default 2).
    pub ramp_in_s: f32,
    /// Contact data older than this trips the watchdog, s (default 0.032).
    pub watchdog_timeout_s: f32,
    /// Ramp-out time once the watchdog trips, s (default 0.05).
    pub ramp_out_s: f32,
}

impl SafetyConfig {
    /// Defaults for a device with the given peak force (N) and torque (N·m).
    pub fn for_limits(max_force_n: f32, max_torque_nm: f32) -> Self {
        Self {
            max_force_n,
            max_torque_nm,
            max_force_rate_n_per_s: 500.0,
            max_torque_rate_nm_per_s: 10.0,
            engage_threshold_n: 0.2,
            engage_ticks: 3,
            ramp_in_s: 2.0,
            watchdog_timeout_s: 0.032,
            ramp_out_s: 0.05,
        }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        non_negative("max_force_n", self.max_force_n)?;
        non_negative("max_torque_nm", self.max_torque_nm)?;
        positive("max_force_rate_n_per_s", self.max_force_rate_n_per_s)?;
        positive("max_torque_rate_nm_per_s", self.max_torque_rate_nm_per_s)?;
        non_negative("engage_threshold_n", self.engage_threshold_n)?;
        positive("ramp_in_s", self.ramp_in_s)?;
        positive("watchdog_timeout_s", self.watchdog_timeout_s)?;
        positive("ramp_out_s", self.ramp_out_s)
    }
}

/// Where the layer stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SafetyPhase {
    /// Output is zero until the request is small for long enough.
    WaitingForSmallForce,
    /// Output gain rises from 0 to 1.
    RampingIn,
    /// Output follows the request (within limits).
    Engaged,
}

/// Counters for telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SafetyStats {
    /// Requests that held NaN or infinity.
    pub non_finite: u64,
    /// Ticks whose target exceeded a clamp.
    pub clamped: u64,
    /// Ticks whose output was held back by the rate limit.
    pub rate_limited: u64,
    /// Ticks with stale contact data.
    pub stale: u64,
}

/// The safety layer's state (one per device).
#[derive(Clone, Debug)]
pub struct SafetyLayer {
    config: SafetyConfig,
    phase: SafetyPhase,
    small_ticks: u32,
    engage_gain: f32,
    watchdog_gain: f32,
    last: ForceTorque,
    stats: SafetyStats,
}

impl SafetyLayer {
    /// A layer waiting for a small force, output zero.
    pub fn new(config: SafetyConfig) -> Self {
        Self {
            config,
            phase: SafetyPhase::WaitingForSmallForce,
            small_ticks: 0,
            engage_gain: 0.0,
            watchdog_gain: 1.0,
            last: ForceTorque::ZERO,
            stats: SafetyStats::default(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &SafetyConfig {
        &self.config
    }

    /// The current phase.
    pub fn phase(&self) -> SafetyPhase {
        self.phase
    }

    /// The counters.
    pub fn stats(&self) -> SafetyStats {
        self.stats
    }

    /// The last output.
    pub fn last_output(&self) -> ForceTorque {
        self.last
    }

    /// The combined gain (engagement × watchdog) applied on the last tick, 0..=1.
    pub fn gain(&self) -> f32 {
        self.engage_gain * self.watchdog_gain
    }

    /// Goes back to waiting for a small force (e.g. after the user put the stylus down).
    pub fn disengage(&mut self) {
        self.phase = SafetyPhase::WaitingForSmallForce;
        self.small_ticks = 0;
        self.engage_gain = 0.0;
    }

    /// Filters `requested` for a tick of `dt_s` seconds, given that the contact data behind it is
    /// `data_age_s` seconds old. Always returns finite values within the limits. Allocation-free.
    pub fn apply(&mut self, requested: ForceTorque, dt_s: f32, data_age_s: f32) -> ForceTorque {
        let c = self.config;
        let dt = if dt_s.is_finite() { dt_s.clamp(0.0, 0.1) } else { 0.0 };
        let mut req = requested;
        if !req.force.is_finite() {
            req.force = Vec3::ZERO;
            self.stats.non_finite += 1;
        }
        if !req.torque.is_finite() {
            req.torque = Vec3::ZERO;
            self.stats.non_finite += 1;
        }

        match self.phase {
            SafetyPhase::WaitingForSmallForce => {
                if req.force.length() < c.engage_threshold_n {
                    self.small_ticks += 1;
                    if self.small_ticks > c.engage_ticks {
                        self.phase = SafetyPhase::RampingIn;
                    }
                } else {
                    self.small_ticks = 0;
                }
                self.engage_gain = 0.0;
            }
            SafetyPhase::RampingIn => {
                self.engage_gain = (self.engage_gain + dt / c.ramp_in_s).min(1.0);
                if self.engage_gain >= 1.0 {
                    self.phase = SafetyPhase::Engaged;
                }
            }
            SafetyPhase::Engaged => self.engage_gain = 1.0,
        }

        let stale = !(data_age_s.is_finite() && data_age_s <= c.watchdog_timeout_s);
        if stale {
            self.stats.stale += 1;
            self.watchdog_gain = (self.watchdog_gain - dt / c.ramp_out_s).max(0.0);
        } else {
            self.watchdog_gain = (self.watchdog_gain + dt / c.ramp_in_s).min(1.0);
        }

        let gain = self.engage_gain * self.watchdog_gain;
        let mut target = ForceTorque { force: req.force * gain, torque: req.torque * gain };
        if target.force.length() > c.max_force_n || target.torque.length() > c.max_torque_nm {
            self.stats.clamped += 1;
        }
        target.force = target.force.clamp_length_max(c.max_force_n);
        target.torque = target.torque.clamp_length_max(c.max_torque_nm);

        let df = (target.force - self.last.force).clamp_length_max(c.max_force_rate_n_per_s * dt);
        let dtau = (target.torque - self.last.torque).clamp_length_max(c.max_torque_rate_nm_per_s * dt);
        let mut out = ForceTorque { force: self.last.force + df, torque: self.last.torque + dtau };
        if out.force != target.force || out.torque != target.torque {
            self.stats.rate_limited += 1;
        }
        // Both ends lie in the clamp ball, so the step does too; clamp again against rounding.
        out.force = out.force.clamp_length_max(c.max_force_n);
        out.torque = out.torque.clamp_length_max(c.max_torque_nm);
        if !out.is_finite() {
            out = ForceTorque::ZERO;
        }
        self.last = out;
        out
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    const DT: f32 = 0.001;

    fn ft(x: f32) -> ForceTorque {
        ForceTorque { force: Vec3::new(x, 0.0, 0.0), torque: Vec3::ZERO }
    }

    fn engaged(config: SafetyConfig) -> SafetyLayer {
        let mut s = SafetyLayer::new(config);
        for _ in 0..3000 {
            s.apply(ForceTorque::ZERO, DT, 0.0);
        }
        assert_eq!(s.phase(), SafetyPhase::Engaged);
        s
    }

    #[test]
    fn nothing_is_output_until_the_request_stays_small_for_more_than_three_ticks() {
        let mut s = SafetyLayer::new(SafetyConfig::for_limits(3.3, 0.0));
        for _ in 0..100 {
            assert_eq!(s.apply(ft(1.0), DT, 0.0), ForceTorque::ZERO);
        }
        for _ in 0..4 {
            s.apply(ft(0.1), DT, 0.0);
        }
        assert_eq!(s.phase(), SafetyPhase::RampingIn);
    }

    #[test]
    fn forces_ramp_in_over_two_seconds_after_engagement() {
        let mut s = SafetyLayer::new(SafetyConfig::for_limits(3.3, 0.0));
        for _ in 0..4 {
            s.apply(ForceTorque::ZERO, DT, 0.0);
        }
        let mut at_half = 0.0;
        for i in 0..2100 {
            let out = s.apply(ft(1.0), DT, 0.0);
            if i == 999 {
                at_half = out.force.x;
            }
        }
        assert!((at_half - 0.5).abs() < 0.01, "{at_half}");
        assert_eq!(s.phase(), SafetyPhase::Engaged);
        assert!((s.last_output().force.x - 1.0).abs() < 1e-4);
    }

    #[test]
    fn output_never_exceeds_the_peak_force_or_torque() {
        let mut s = engaged(SafetyConfig::for_limits(3.3, 0.1));
        for _ in 0..1000 {
            let out = s.apply(ForceTorque { force: Vec3::splat(100.0), torque: Vec3::splat(5.0) }, DT, 0.0);
            assert!(out.force.length() <= 3.3 + 1e-5 && out.torque.length() <= 0.1 + 1e-6);
        }
        assert!(s.stats().clamped > 0);
    }

    #[test]
    fn a_step_request_is_spread_over_ticks_by_the_rate_limit() {
        let mut s = engaged(SafetyConfig::for_limits(8.0, 0.0));
        let out = s.apply(ft(5.0), DT, 0.0);
        assert!((out.force.x - 0.5).abs() < 1e-5, "500 N/s at 1 ms is 0.5 N per tick");
        let mut previous = out;
        for _ in 0..20 {
            let out = s.apply(ft(-5.0), DT, 0.0);
            assert!((out.force - previous.force).length() <= 0.5 + 1e-5);
            previous = out;
        }
    }

    #[test]
    fn the_watchdog_ramps_force_to_zero_when_contact_data_goes_stale() {
        let mut s = engaged(SafetyConfig::for_limits(3.3, 0.0));
        for _ in 0..100 {
            s.apply(ft(2.0), DT, 0.001);
        }
        assert!((s.last_output().force.x - 2.0).abs() < 1e-4);
        let mut previous = s.last_output().force.x;
        for i in 0..60 {
            let out = s.apply(ft(2.0), DT, 0.040 + i as f32 * DT).force.x;
            assert!(out <= previous + 1e-6, "monotonic ramp-down");
            previous = out;
        }
        assert_eq!(s.last_output(), ForceTorque::ZERO);
        assert!(s.stats().stale >= 60);
    }

    #[test]
    fn nan_and_infinite_requests_never_reach_the_output() {
        let mut s = engaged(SafetyConfig::for_limits(3.3, 0.2));
        let out =
            s.apply(ForceTorque { force: Vec3::new(f32::NAN, 1.0, 0.0), torque: Vec3::splat(f32::INFINITY) }, DT, 0.0);
        assert!(out.is_finite());
        assert!(s.apply(ft(1.0), f32::NAN, f32::NAN).is_finite());
        assert_eq!(s.stats().non_finite, 2);
    }

    proptest! {
        #[test]
        fn any_request_sequence_stays_within_limits_and_rate(
            requests in prop::collection::vec((-1e6f32..1e6, -1e6f32..1e6, -1e3f32..1e3, 0.0f32..0.002, 0.0f32..0.05), 1..300)
        ) {
            let cfg = SafetyConfig { ramp_in_s: 0.01, ..SafetyConfig::for_limits(8.5, 0.188) };
            let mut s = SafetyLayer::new(cfg);
            let mut last = ForceTorque::ZERO;
            for (fx, fy, tz, dt, age) in requests {
                let out = s.apply(ForceTorque { force: Vec3::new(fx, fy, 0.0), torque: Vec3::new(0.0, 0.0, tz) }, dt, age);
                prop_assert!(out.is_finite());
                prop_assert!(out.force.length() <= 8.5 + 1e-4);
                prop_assert!(out.torque.length() <= 0.188 + 1e-5);
                prop_assert!((out.force - last.force).length() <= cfg.max_force_rate_n_per_s * dt + 1e-4);
                last = out;
            }
        }
    }
}
