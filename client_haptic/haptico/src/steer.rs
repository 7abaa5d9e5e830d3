//! A simulated device whose hand the game steers: the latest [`HandGoal`] (hold, a line, an orbit, a
//! ring of pokes) reaches the haptic thread through a triple buffer, which samples it at each tick.
//!
//! You need this module to move a [`SimDevice`] from a game thread (keys, a mouse, a bot, a scripted
//! path) while the haptic thread renders forces on it: [`SteeredSim::new`] gives the device and its
//! [`HandControl`]. Neither end waits for the other.

use std::f32::consts::TAU;

use glam::Vec3;
use haptic_common::{DeviceState, ForceTorque, Pose};

use crate::sim::{SimConfig, SimDevice, TargetPath};
use crate::{Device, DeviceSpecs};

/// Where the simulated hand wants the stylus, sampled on the haptic thread at each tick (device frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HandGoal {
    /// Stay at one pose.
    Hold(Pose),
    /// Go around a vertical circle: `centre` + `radius`·(cos φ, 0, −sin φ), φ = `start_rad` + 2π·turns
    /// done, one turn per `period_s`, starting at `start_us` on the haptic clock; holds at the end.
    Orbit {
        /// Centre of the circle, m.
        centre: Vec3,
        /// Radius, m.
        radius: f32,
        /// Angle at the start, rad.
        start_rad: f32,
        /// Seconds per turn.
        period_s: f32,
        /// Turns to make (negative: clockwise, seen from above).
        turns: f32,
        /// Haptic-clock time of the start, µs.
        start_us: u64,
    },
    /// A ring of `n` radial pokes around the vertical axis through `centre`, one per `tap_s` from
    /// `start_us`: in from `r_out` to `r_in` (first 40 %), stay (to 60 %), out (to 90 %), then round to the
    /// next angle at `r_out`; back at the first angle after the last poke.
    Taps {
        /// A point on the axis, at the pokes' height, m.
        centre: Vec3,
        /// Radius where each poke starts, m.
        r_out: f32,
        /// Radius each poke reaches for, m.
        r_in: f32,
        /// Number of pokes.
        n: u32,
        /// Seconds per poke.
        tap_s: f32,
        /// Haptic-clock time of the start, µs.
        start_us: u64,
    },
    /// Move in a straight line from `from` to `to` in `duration_s` from `start_us`, then hold.
    Line {
        /// Start, m.
        from: Vec3,
        /// End, m.
        to: Vec3,
        /// Seconds.
        duration_s: f32,
        /// Haptic-clock time of the start, µs.
        start_us: u64,
    },
}

impl HandGoal {
    /// The goal's pose at haptic-clock time `t_us`. Pure and allocation-free.
    pub fn sample(&self, t_us: u64) -> Pose {
        let since = |start_us: u64| t_us.saturating_sub(start_us) as f32 * 1e-6;
        match *self {
            Self::Hold(p) => p,
            Self::Orbit { centre, radius, start_rad, period_s, turns, start_us } => {
                let done = (since(start_us) / period_s.max(1e-3)).min(turns.abs()) * turns.signum();
                let phi = start_rad + TAU * done;
                Pose::from_translation(centre + radius * Vec3::new(phi.cos(), 0.0, -phi.sin()))
            }
            Self::Line { from, to, duration_s, start_us } => {
                let s = (since(start_us) / duration_s.max(1e-3)).min(1.0);
                Pose::from_translation(from.lerp(to, s))
            }
            Self::Taps { centre, r_out, r_in, n, tap_s, start_us } => {
                let n = n.max(1) as f32;
                let t = (since(start_us) / tap_s.max(1e-3)).min(n);
                let (k, u) = (t.floor(), t.fract());
                let lerp = |a: f32, b: f32, s: f32| a + (b - a) * s;
                let (r, turn) = match u {
                    _ if t >= n => (r_out, n),
                    u if u < 0.4 => (lerp(r_out, r_in, u / 0.4), k),
                    u if u < 0.6 => (r_in, k),
                    u if u < 0.9 => (lerp(r_in, r_out, (u - 0.6) / 0.3), k),
                    u => (r_out, k + (u - 0.9) / 0.1),
                };
                let phi = TAU * turn / n;
                Pose::from_translation(centre + r * Vec3::new(phi.cos(), 0.0, -phi.sin()))
            }
        }
    }

    /// True once the goal has stopped moving at `t_us`.
    pub fn finished(&self, t_us: u64) -> bool {
        let since = |start_us: u64| t_us.saturating_sub(start_us) as f32 * 1e-6;
        match *self {
            Self::Hold(_) => true,
            Self::Orbit { period_s, turns, start_us, .. } => since(start_us) >= period_s * turns.abs(),
            Self::Line { duration_s, start_us, .. } => since(start_us) >= duration_s,
            Self::Taps { n, tap_s, start_us, .. } => since(start_us) >= n as f32 * tap_s,
        }
    }
}

/// The game thread's end of a steerable simulated hand.
pub struct HandControl {
    input: triple_buffer::Input<HandGoal>,
    latest: HandGoal,
}

impl HandControl {
    /// Sets where the hand goes from now on.
    pub fn set(&mut self, goal: HandGoal) {
        self.latest = goal;
        self.input.write(goal);
    }

    /// The goal last set.
    pub fn goal(&self) -> HandGoal {
        self.latest
    }
}

impl std::fmt::Debug for HandControl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HandControl").field("latest", &self.latest).finish()
    }
}

/// A [`SimDevice`] whose hand follows the latest [`HandGoal`] from a [`HandControl`].
pub struct SteeredSim {
    sim: SimDevice,
    goal: triple_buffer::Output<HandGoal>,
}

impl SteeredSim {
    /// A simulated `specs` device resting at `start`, and the handle that steers it.
    pub fn new(specs: DeviceSpecs, start: Pose) -> (Self, HandControl) {
        let (input, goal) = triple_buffer::triple_buffer(&HandGoal::Hold(start));
        let sim = SimDevice::new(SimConfig::new(specs), TargetPath::Hold(start));
        (Self { sim, goal }, HandControl { input, latest: HandGoal::Hold(start) })
    }
}

impl Device for SteeredSim {
    fn specs(&self) -> &DeviceSpecs {
        self.sim.specs()
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        let target = self.goal.read().sample(t_us);
        // `Hold` owns no heap memory: replacing the path neither allocates nor frees.
        self.sim.set_path(TargetPath::Hold(target));
        self.sim.read_state(t_us)
    }

    fn command(&mut self, ft: ForceTorque) {
        self.sim.command(ft);
    }

    fn release(&mut self) {
        self.sim.release();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_goes_round_once_and_holds() {
        let goal = HandGoal::Orbit {
            centre: Vec3::Y,
            radius: 0.1,
            start_rad: 0.0,
            period_s: 2.0,
            turns: 1.0,
            start_us: 1_000_000,
        };
        let at = |s: f64| goal.sample((s * 1e6) as u64).translation;
        assert!((at(0.0) - Vec3::new(0.1, 1.0, 0.0)).length() < 1e-5, "holds the start before it begins");
        assert!((at(1.5) - Vec3::new(0.0, 1.0, -0.1)).length() < 1e-5, "a quarter turn after half a second");
        assert!((at(3.0) - Vec3::new(0.1, 1.0, 0.0)).length() < 1e-4);
        assert!((at(9.0) - at(3.0)).length() < 1e-4, "holds after one turn");
        assert!(!goal.finished(2_900_000) && goal.finished(3_000_000));
    }

    #[test]
    fn an_orbit_of_negative_turns_goes_clockwise() {
        let goal = HandGoal::Orbit {
            centre: Vec3::ZERO,
            radius: 0.1,
            start_rad: 0.0,
            period_s: 2.0,
            turns: -0.25,
            start_us: 0,
        };
        let at = |s: f64| goal.sample((s * 1e6) as u64).translation;
        assert!(at(0.25).z > 0.05 && at(0.25).x > 0.05, "halfway, clockwise: {}", at(0.25));
        assert!((at(0.5) - Vec3::new(0.0, 0.0, 0.1)).length() < 1e-4, "a quarter turn clockwise: {}", at(0.5));
        assert!((at(5.0) - at(0.5)).length() < 1e-6, "then holds");
        assert!(!goal.finished(400_000) && goal.finished(500_000));
    }

    #[test]
    fn the_steered_hand_reaches_a_new_goal() {
        let (mut device, mut control) = SteeredSim::new(crate::presets::phantom_desktop(), Pose::IDENTITY);
        control.set(HandGoal::Hold(Pose::from_translation(Vec3::new(0.02, 0.0, 0.0))));
        let mut state = device.read_state(0);
        for tick in 1..2000 {
            state = device.read_state(tick * 1000);
        }
        assert!((state.pose.translation.x - 0.02).abs() < 1e-3, "{:?}", state.pose.translation);
    }
}
