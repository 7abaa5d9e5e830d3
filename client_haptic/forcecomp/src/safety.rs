//! The safety layer, applied last to every force before it reaches a device: engagement, watchdog,
//! clamps, force-rate limit, and NaN/inf removal (the habits of CHAI3D, OpenHaptics and Force Dimension).
//!
//! You need this module whenever forces go to real hardware; the order inside [`SafetyLayer::apply`] is:
//! 1. non-finite requests become zero (counted);
//! 2. **engagement**: output stays zero until the request has stayed below `engage_threshold_n` for more
//!    than `engage_ticks` ticks, then the gain ramps from 0 to 1 over `ramp_in_s`;
//! 3. **watchdog**: when the contact data is older than `watchdog_timeout_s`, the gain ramps to zero over
//!    `ramp_out_s`; fresh data ramps it back over `ramp_in_s`;
//! 4. **workspace**: with a [`Workspace`], forces engage only while the grip is inside it, and disengage
//!    (back to step 2) when it goes [`Workspace::LEAVE`] times its radius from its centre — a grip read
//!    outside where the device can be is a device that is not homed or not centred;
//! 5. **clamp** to `max_force_n` / `max_torque_nm`, and to less as the device heats: once the force's
//!    mean square over `heat_time_s` passes half of `continuous_force_n`², the limit slides from the peak
//!    force down to the continuous one (reached at the whole square), so the peak is there for a touch and
//!    a long push settles at the continuous force (10 N on the Inverse3 holds for about 2.5 s, then slides
//!    to 4 N);
//! 6. **rate limit**: the output moves towards the target by at most `max_force_rate_n_per_s · dt` (and
//!    the torque likewise), so no tick kicks.

use glam::Vec3;
use haptic_common::ForceTorque;

use crate::error::{ForceCompError, Result, non_negative, positive};

/// [`SafetyConfig::watchdog_timeout_s`]'s default, s: contact data older than this trips the watchdog.
pub const DEFAULT_WATCHDOG_TIMEOUT_S: f32 = 0.032;
/// [`SafetyConfig::ramp_in_s`]'s default, s.
pub const DEFAULT_RAMP_IN_S: f32 = 2.0;

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
    /// Ramp-in time after engagement or after the watchdog recovers, s (default [`DEFAULT_RAMP_IN_S`]).
    pub ramp_in_s: f32,
    /// Contact data older than this trips the watchdog, s (default [`DEFAULT_WATCHDOG_TIMEOUT_S`]).
    pub watchdog_timeout_s: f32,
    /// Ramp-out time once the watchdog trips, s (default 0.05).
    pub ramp_out_s: f32,
    /// The force the device can hold for long, N (its continuous force; default: `max_force_n`, no
    /// heating limit).
    pub continuous_force_n: f32,
    /// Time constant of the force's mean square that stands for the motors' heat, s (default 30).
    pub heat_time_s: f32,
    /// Where the grip may be for forces to engage (device frame); `None`: anywhere (default).
    pub workspace: Option<Workspace>,
}

/// A ball in the device frame where the grip must be for forces to engage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Workspace {
    /// Its centre, m.
    pub centre: Vec3,
    /// Its radius, m.
    pub radius_m: f32,
}

impl Workspace {
    /// Forces engaged disengage when the grip is this many radii from the centre (the ball is the
    /// device's published workspace; its real reach goes a little beyond in places).
    pub const LEAVE: f32 = 1.5;

    /// True when `p` is inside the ball.
    pub fn holds(&self, p: Vec3) -> bool {
        p.distance(self.centre) <= self.radius_m
    }

    /// True when `p` is so far out that forces must stop (or is no position at all: NaN).
    pub fn lost(&self, p: Vec3) -> bool {
        let d = p.distance(self.centre);
        d.is_nan() || d > Self::LEAVE * self.radius_m
    }
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
            ramp_in_s: DEFAULT_RAMP_IN_S,
            watchdog_timeout_s: DEFAULT_WATCHDOG_TIMEOUT_S,
            ramp_out_s: 0.05,
            continuous_force_n: max_force_n,
            heat_time_s: 30.0,
            workspace: None,
        }
    }

    /// The same limits, heating down to `continuous_force_n` (at most the peak force) on a long push.
    pub fn with_continuous_force(self, continuous_force_n: f32) -> Self {
        Self { continuous_force_n: continuous_force_n.min(self.max_force_n), ..self }
    }

    /// The same limits, engaging forces only while the grip is inside `workspace`.
    pub fn with_workspace(self, workspace: Workspace) -> Self {
        Self { workspace: Some(workspace), ..self }
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
        positive("ramp_out_s", self.ramp_out_s)?;
        non_negative("continuous_force_n", self.continuous_force_n)?;
        positive("heat_time_s", self.heat_time_s)?;
        if let Some(w) = self.workspace {
            positive("workspace.radius_m", w.radius_m)?;
            let c = w.centre;
            for (name, value) in [("workspace.centre.x", c.x), ("workspace.centre.y", c.y), ("workspace.centre.z", c.z)]
            {
                if !value.is_finite() {
                    return Err(ForceCompError::OutOfRange { name, value, expected: "finite" });
                }
            }
        }
        Ok(())
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
    /// Ticks with the grip outside the workspace while forces were not engaged, or far enough out to
    /// disengage them.
    pub outside_workspace: u64,
    /// Ticks whose limit was below the peak force because the device had been pushing long and hard.
    pub heat_limited: u64,
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
    heat_n2: f32,
    outside: bool,
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
            heat_n2: 0.0,
            outside: false,
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

    /// True when, on the last tick, the grip was outside the workspace with forces off for it.
    pub fn outside_workspace(&self) -> bool {
        self.outside
    }

    /// The largest force allowed now, N: the peak force, less once the device has pushed long and hard.
    pub fn force_limit_n(&self) -> f32 {
        let c = &self.config;
        let half = 0.5 * c.continuous_force_n * c.continuous_force_n;
        if c.continuous_force_n >= c.max_force_n || self.heat_n2 <= half {
            return c.max_force_n;
        }
        let over = ((self.heat_n2 - half) / half.max(f32::MIN_POSITIVE)).min(1.0);
        c.max_force_n + (c.continuous_force_n - c.max_force_n) * over
    }

    /// Goes back to waiting for a small force (e.g. after the user put the stylus down).
    pub fn disengage(&mut self) {
        self.phase = SafetyPhase::WaitingForSmallForce;
        self.small_ticks = 0;
        self.engage_gain = 0.0;
    }

    /// Filters `requested` for a tick of `dt_s` seconds, given that the contact data behind it is
    /// `data_age_s` seconds old, with no grip position (a configured workspace then never lets forces
    /// engage). Always returns finite values within the limits. Allocation-free.
    pub fn apply(&mut self, requested: ForceTorque, dt_s: f32, data_age_s: f32) -> ForceTorque {
        self.apply_at(requested, dt_s, data_age_s, Vec3::NAN)
    }

    /// [`Self::apply`] with the grip at `grip` (device frame, m), checked against the workspace.
    pub fn apply_at(&mut self, requested: ForceTorque, dt_s: f32, data_age_s: f32, grip: Vec3) -> ForceTorque {
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

        let (inside, lost) = match c.workspace {
            Some(w) => (w.holds(grip), w.lost(grip)),
            None => (true, false),
        };
        if lost && self.phase != SafetyPhase::WaitingForSmallForce {
            self.disengage();
        }
        // Lost means disengaged by now: outside with forces off either way.
        self.outside = !inside && self.phase == SafetyPhase::WaitingForSmallForce;
        if self.outside {
            self.stats.outside_workspace += 1;
        }

        match self.phase {
            SafetyPhase::WaitingForSmallForce => {
                if !inside {
                    self.small_ticks = 0;
                } else if req.force.length() < c.engage_threshold_n {
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
        let limit = self.force_limit_n();
        if limit < c.max_force_n {
            self.stats.heat_limited += 1;
        }
        let mut target = ForceTorque { force: req.force * gain, torque: req.torque * gain };
        if target.force.length() > limit || target.torque.length() > c.max_torque_nm {
            self.stats.clamped += 1;
        }
        target.force = target.force.clamp_length_max(limit);
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
        let heat = out.force.length_squared() - self.heat_n2;
        self.heat_n2 = (self.heat_n2 + heat * (dt / c.heat_time_s).min(1.0)).max(0.0);
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

    fn ball() -> Workspace {
        Workspace { centre: Vec3::new(0.0, 0.0, 0.11), radius_m: 0.04 }
    }

    #[test]
    fn with_a_workspace_forces_engage_only_with_the_grip_inside_and_stop_when_it_goes_far_out() {
        let cfg = SafetyConfig { ramp_in_s: 0.01, ..SafetyConfig::for_limits(8.0, 0.0).with_workspace(ball()) };
        let mut s = SafetyLayer::new(cfg);
        let outside = Vec3::new(0.0, 0.0, 0.2);
        for _ in 0..100 {
            assert_eq!(s.apply_at(ForceTorque::ZERO, DT, 0.0, outside), ForceTorque::ZERO);
        }
        assert_eq!(s.phase(), SafetyPhase::WaitingForSmallForce, "a grip read out of reach never engages");
        assert!(s.outside_workspace() && s.stats().outside_workspace == 100);
        // No position at all (NaN) is not inside either.
        s.apply(ForceTorque::ZERO, DT, 0.0);
        assert_eq!(s.phase(), SafetyPhase::WaitingForSmallForce);
        // Inside: engages as usual.
        let inside = Vec3::new(0.03, 0.0, 0.11);
        for _ in 0..4 {
            s.apply_at(ft(0.1), DT, 0.0, inside);
        }
        for _ in 0..100 {
            s.apply_at(ft(2.0), DT, 0.0, inside);
        }
        assert_eq!(s.phase(), SafetyPhase::Engaged);
        assert!(!s.outside_workspace());
        assert!((s.last_output().force.x - 2.0).abs() < 1e-4);
        // Pushed a little past the ball (its edge is not a wall): forces stay on.
        s.apply_at(ft(2.0), DT, 0.0, Vec3::new(0.055, 0.0, 0.11));
        assert_eq!(s.phase(), SafetyPhase::Engaged);
        // Read 1.5 radii out: forces go, fall at the rate limit, and wait for the grip to come back.
        let far = Vec3::new(0.061, 0.0, 0.11);
        let mut previous = s.last_output().force.x;
        for _ in 0..10 {
            let out = s.apply_at(ft(2.0), DT, 0.0, far).force.x;
            assert!(out <= previous && previous - out <= 0.5 + 1e-5, "down by ≤ 0.5 N a tick: {previous} → {out}");
            previous = out;
        }
        assert_eq!(s.last_output(), ForceTorque::ZERO);
        assert_eq!(s.phase(), SafetyPhase::WaitingForSmallForce);
        assert!(s.outside_workspace());
        // Back inside with a small request: engages again.
        for _ in 0..4 {
            s.apply_at(ForceTorque::ZERO, DT, 0.0, inside);
        }
        assert_eq!(s.phase(), SafetyPhase::RampingIn);
    }

    #[test]
    fn a_long_hard_push_heats_the_limit_down_to_the_continuous_force_and_a_touch_keeps_the_peak() {
        // The Inverse3's figures: 10 N peak, 4 N for long.
        let mut s = engaged(SafetyConfig::for_limits(10.0, 0.0).with_continuous_force(4.0));
        assert_eq!(s.config().heat_time_s, 30.0);
        // A one-second 10 N press, then rest: the peak is there, and the limit never moves.
        for _ in 0..1000 {
            s.apply(ft(10.0), DT, 0.0);
        }
        assert!((s.last_output().force.x - 10.0).abs() < 1e-4, "{:?}", s.last_output());
        assert_eq!(s.stats().heat_limited, 0);
        for _ in 0..60_000 {
            s.apply(ForceTorque::ZERO, DT, 0.0);
        }
        // A two-minute push at the peak: the limit slides down to about the continuous force and stays.
        let mut least = f32::MAX;
        let mut at = Vec::new();
        for i in 0..120_000 {
            let out = s.apply(ft(10.0), DT, 0.0).force.x;
            if i >= 20 {
                least = least.min(out); // after the 20 ticks the rate limit takes to reach 10 N
            }
            if i == 2_000 {
                assert!((out - 10.0).abs() < 1e-4, "the peak is there for the first two seconds: {out}");
            }
            if i % 10_000 == 9_999 {
                at.push(out);
            }
        }
        assert!(s.stats().heat_limited > 0);
        let end = *at.last().expect("sampled");
        assert!((4.0..=4.05).contains(&end), "held at {end} N after two minutes: {at:?}");
        assert!(least >= 4.0 - 1e-4, "never below the continuous force: {least}");
        assert!(at.windows(2).all(|w| w[1] <= w[0] + 1e-3), "falls, never climbs back while pushed: {at:?}");
        // With no continuous figure there is no heating limit.
        let mut cold = engaged(SafetyConfig::for_limits(10.0, 0.0));
        for _ in 0..60_000 {
            cold.apply(ft(10.0), DT, 0.0);
        }
        assert_eq!(cold.stats().heat_limited, 0);
        assert!((cold.last_output().force.x - 10.0).abs() < 1e-4);
    }

    #[test]
    fn a_workspace_or_heat_figure_that_cannot_work_is_refused_by_name() {
        let bad = |cfg: SafetyConfig| cfg.validate().expect_err("refused").to_string();
        let base = SafetyConfig::for_limits(8.0, 0.0);
        assert!(bad(base.with_workspace(Workspace { radius_m: 0.0, ..ball() })).contains("workspace.radius_m"));
        let nan = Workspace { centre: Vec3::new(0.0, f32::NAN, 0.0), ..ball() };
        assert!(bad(base.with_workspace(nan)).contains("workspace.centre.y"));
        assert!(bad(SafetyConfig { heat_time_s: 0.0, ..base }).contains("heat_time_s"));
        assert!(bad(SafetyConfig { continuous_force_n: -1.0, ..base }).contains("continuous_force_n"));
        assert_eq!(base.with_continuous_force(20.0).continuous_force_n, 8.0, "never above the peak");
        assert!(base.with_workspace(ball()).with_continuous_force(3.0).validate().is_ok());
    }

    proptest! {
        #[test]
        fn any_request_sequence_stays_within_limits_and_rate(
            requests in prop::collection::vec((-1e6f32..1e6, -1e6f32..1e6, -1e3f32..1e3, 0.0f32..0.002, 0.0f32..0.05, -0.1f32..0.1), 1..300)
        ) {
            let cfg = SafetyConfig { ramp_in_s: 0.01, heat_time_s: 0.05, ..SafetyConfig::for_limits(8.5, 0.188) }
                .with_continuous_force(2.0)
                .with_workspace(Workspace { centre: Vec3::ZERO, radius_m: 0.05 });
            let mut s = SafetyLayer::new(cfg);
            let mut last = ForceTorque::ZERO;
            for (fx, fy, tz, dt, age, x) in requests {
                let request = ForceTorque { force: Vec3::new(fx, fy, 0.0), torque: Vec3::new(0.0, 0.0, tz) };
                let out = s.apply_at(request, dt, age, Vec3::new(x, 0.0, 0.0));
                prop_assert!(out.is_finite());
                prop_assert!(out.force.length() <= 8.5 + 1e-4);
                prop_assert!(out.torque.length() <= 0.188 + 1e-5);
                prop_assert!((out.force - last.force).length() <= cfg.max_force_rate_n_per_s * dt + 1e-4);
                last = out;
            }
        }
    }
}
