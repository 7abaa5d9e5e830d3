//! How the threads are keeping up, and what the device was asked to do: the haptic and collision rates
//! over 100 ms windows, the largest force and the largest change of force between two haptic ticks.
//!
//! You need this module to check a set-up (the examples end with these figures as one JSON line) or to
//! show the loop's health in a game. Figures are gathered from every tick, not sampled per frame.

use bevy::prelude::*;

/// Length of a rate window, µs.
pub const WINDOW_US: u64 = 100_000;

/// Events in a window at or above which windows are counted together (2 kHz at 100 ms windows).
const TOP_COUNT: usize = 200;

/// Counts events per [`WINDOW_US`] window and keeps how many complete windows had each rate, so the
/// slowest window, the median and any quantile can be read (exact below 2 kHz: a window's rate is its
/// event count × 10 Hz).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowedRate {
    window: Option<u64>,
    count: u32,
    started: bool,
    min_hz: Option<f32>,
    windows: u32,
    /// Complete windows by their event count (the last entry: [`TOP_COUNT`] events or more).
    by_count: [u32; TOP_COUNT + 1],
}

impl Default for WindowedRate {
    fn default() -> Self {
        WindowedRate { window: None, count: 0, started: false, min_hz: None, windows: 0, by_count: [0; TOP_COUNT + 1] }
    }
}

impl WindowedRate {
    /// Counts an event at `t_us` (in time order).
    pub fn record(&mut self, t_us: u64) {
        let w = t_us / WINDOW_US;
        match self.window {
            None => self.window = Some(w),
            Some(current) if w > current => {
                // The first window is partial (the thread started inside it): not counted.
                if self.started {
                    self.close(self.count);
                }
                // Whole windows without an event.
                for _ in current + 1..w {
                    self.close(0);
                }
                self.started = true;
                self.window = Some(w);
                self.count = 0;
            }
            Some(_) => {}
        }
        self.count += 1;
    }

    fn close(&mut self, count: u32) {
        let hz = count as f32 * (1e6 / WINDOW_US as f32);
        self.min_hz = Some(self.min_hz.map_or(hz, |m| m.min(hz)));
        self.windows += 1;
        self.by_count[(count as usize).min(TOP_COUNT)] += 1;
    }

    /// The rate at or below which a fraction `q` (0–1) of the complete windows ran, Hz (`None` before
    /// one completed). `quantile_hz(0.5)` is the median window; windows of 2 kHz or more count as 2 kHz.
    pub fn quantile_hz(&self, q: f32) -> Option<f32> {
        if self.windows == 0 {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.windows as f32).ceil() as u32).max(1);
        let mut seen = 0;
        let count = self.by_count.iter().position(|&n| {
            seen += n;
            seen >= rank
        })?;
        Some(count as f32 * (1e6 / WINDOW_US as f32))
    }

    /// The smallest rate of a complete window, Hz (`None` before one completed).
    pub fn min_hz(&self) -> Option<f32> {
        self.min_hz
    }

    /// Complete windows seen.
    pub fn windows(&self) -> u32 {
        self.windows
    }
}

/// The loop's figures since the app started (updated in `PreUpdate`).
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct HapticStats {
    /// Haptic ticks per complete 100 ms window.
    pub haptic: WindowedRate,
    /// Collision steps per complete 100 ms window (none without `CollettePlugin`).
    pub collision: WindowedRate,
    /// Haptic ticks recorded.
    pub ticks: u64,
    /// Largest force sent to the device, N.
    pub max_force_n: f32,
    /// Largest change of the device's force between two consecutive ticks, N.
    pub max_force_step_n: f32,
    /// Largest rate of change of the device's force between two consecutive ticks, N/s (a late tick's
    /// larger step over its longer interval; the safety layer bounds this one).
    pub max_force_rate_n_per_s: f32,
    /// Largest torque sent to the device, N·m.
    pub max_torque_nm: f32,
    /// Contacts started so far.
    pub contacts_started: u64,
    /// A force or torque that was not a number (never expected: the safety layer refuses them).
    pub non_finite: bool,
    /// The last tick's force, N (for the next step).
    pub(crate) last_force: Option<Vec3>,
    /// The last timed tick's device time, µs, and force, N.
    pub(crate) last_timed: Option<(u64, Vec3)>,
}

impl HapticStats {
    /// Adds one tick's force sent to the device.
    pub fn record_force(&mut self, force: Vec3, torque: Vec3) {
        self.ticks += 1;
        if !force.is_finite() || !torque.is_finite() {
            self.non_finite = true;
            return;
        }
        self.max_force_n = self.max_force_n.max(force.length());
        self.max_torque_nm = self.max_torque_nm.max(torque.length());
        if let Some(last) = self.last_force {
            self.max_force_step_n = self.max_force_step_n.max((force - last).length());
        }
        self.last_force = Some(force);
    }

    /// Adds one tick's force sent to the device at device time `t_us`: [`HapticStats::record_force`] and
    /// the rate of change since the previous timed tick.
    pub fn record_force_at(&mut self, t_us: u64, force: Vec3, torque: Vec3) {
        self.record_force(force, torque);
        if !force.is_finite() {
            return;
        }
        if let Some((t0, f0)) = self.last_timed
            && t_us > t0
        {
            let rate = (force - f0).length() / ((t_us - t0) as f32 * 1e-6);
            self.max_force_rate_n_per_s = self.max_force_rate_n_per_s.max(rate);
        }
        self.last_timed = Some((t_us, force));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slowest_complete_window_is_kept_and_the_partial_first_is_not() {
        let mut rate = WindowedRate::default();
        // Starts 50 ms into a window at 1 kHz, then a window at 500 Hz, then a silent one, then 1 kHz.
        (50..100).for_each(|ms| rate.record(ms * 1000));
        (100..200).for_each(|ms| rate.record(ms * 1000));
        (200..300).step_by(2).for_each(|ms| rate.record(ms * 1000));
        assert_eq!(rate.min_hz(), Some(1000.0), "one complete window so far");
        (400..500).for_each(|ms| rate.record(ms * 1000));
        (500..501).for_each(|ms| rate.record(ms * 1000));
        assert_eq!(rate.windows(), 4, "100-200, 200-300, 300-400 (silent) and 400-500");
        assert_eq!(rate.min_hz(), Some(0.0));
        assert_eq!(rate.quantile_hz(0.0), Some(0.0), "the slowest");
        assert_eq!(rate.quantile_hz(0.5), Some(500.0), "0, 500, 1000, 1000: the second");
        assert_eq!(rate.quantile_hz(0.75), Some(1000.0));
        assert_eq!(WindowedRate::default().quantile_hz(0.5), None);
    }

    #[test]
    fn force_steps_are_between_consecutive_ticks() {
        let mut stats = HapticStats::default();
        stats.record_force(Vec3::ZERO, Vec3::ZERO);
        stats.record_force(Vec3::X * 2.0, Vec3::ZERO);
        stats.record_force(Vec3::X * 2.5, Vec3::ZERO);
        assert_eq!((stats.max_force_n, stats.max_force_step_n, stats.ticks), (2.5, 2.0, 3));
        let mut timed = HapticStats::default();
        timed.record_force_at(1_000, Vec3::ZERO, Vec3::ZERO);
        timed.record_force_at(2_000, Vec3::X * 0.5, Vec3::ZERO);
        timed.record_force_at(5_000, Vec3::X * 1.5, Vec3::ZERO);
        assert_eq!(timed.max_force_step_n, 1.0, "the late tick's step");
        assert!((timed.max_force_rate_n_per_s - 500.0).abs() < 1e-3, "{}", timed.max_force_rate_n_per_s);
        stats.record_force(Vec3::NAN, Vec3::ZERO);
        assert!(stats.non_finite);
    }
}
