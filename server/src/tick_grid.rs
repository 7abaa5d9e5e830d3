//! The served game loop's clock: a grid of deadlines one fixed step apart, so that each update of a
//! shard, its clock set to a deadline, runs exactly one fixed step.

use std::time::{Duration, Instant};

/// Deadlines `period` apart from `start`; [`TickGrid::next`] walks them.
#[derive(Debug)]
pub(crate) struct TickGrid {
    start: Instant,
    /// One fixed step, in nanoseconds.
    period_ns: u64,
    tick: u64,
}

impl TickGrid {
    /// A grid from `start`, one deadline every `period`: the shards' fixed step (`Time::<Fixed>::timestep`),
    /// to the nanosecond, or their updates would drift across its boundaries.
    pub(crate) fn new(start: Instant, period: Duration) -> Self {
        Self { start, period_ns: period.as_nanos().clamp(1, u128::from(u64::MAX)) as u64, tick: 0 }
    }

    /// The next deadline: the next tick's, or, when the loop has fallen behind `now`, the latest deadline
    /// already past (an update at it runs every fixed step missed).
    pub(crate) fn next(&mut self, now: Instant) -> Instant {
        let behind = (now.saturating_duration_since(self.start).as_nanos() / u128::from(self.period_ns)) as u64;
        self.tick = (self.tick + 1).max(behind);
        self.start + Duration::from_nanos(self.period_ns.saturating_mul(self.tick))
    }
}

#[cfg(test)]
mod tests {
    use bevy::prelude::*;
    use bevy::time::{TimePlugin, TimeUpdateStrategy};

    use super::*;

    #[derive(Resource, Default)]
    struct Steps(u64);

    #[test]
    fn deadlines_follow_the_grid_and_a_late_loop_jumps_to_the_latest_past() {
        let start = Instant::now();
        let period = Duration::from_nanos(16_666_667);
        let mut grid = TickGrid::new(start, period);
        assert_eq!(grid.next(start), start + period);
        assert_eq!(grid.next(start + period / 2), start + period * 2, "early: the next tick");
        assert_eq!(grid.next(start + period * 7 + period / 2), start + period * 7, "late: the latest one past");
        assert_eq!(grid.next(start + period * 7 + period / 2), start + period * 8);
    }

    /// The shard's side: updates at the grid's deadlines run one fixed step each, and after a stall the
    /// one update runs every step missed, with no drift between the grid and the fixed clock.
    #[test]
    fn an_app_updated_at_the_deadlines_runs_one_fixed_step_each() {
        let mut app = App::new();
        app.add_plugins(TimePlugin)
            .insert_resource(Time::<Fixed>::from_hz(60.0))
            .init_resource::<Steps>()
            .add_systems(FixedUpdate, |mut steps: ResMut<Steps>| steps.0 += 1);
        let start = Instant::now();
        let period = app.world().resource::<Time<Fixed>>().timestep();
        let mut grid = TickGrid::new(start, period);
        let mut update = |app: &mut App, now: Instant| {
            let deadline = grid.next(now);
            app.insert_resource(TimeUpdateStrategy::ManualInstant(deadline));
            let before = app.world().resource::<Steps>().0;
            app.update();
            app.world().resource::<Steps>().0 - before
        };
        // The first update starts the clock (no time has passed for it).
        assert_eq!(update(&mut app, start), 0);
        for k in 2..=100_000u32 {
            assert_eq!(update(&mut app, start + period * k - Duration::from_micros(300)), 1, "update {k}");
        }
        // Four ticks lost to a stall: the next update catches up with five steps, then one again.
        assert_eq!(update(&mut app, start + period * 100_005 + Duration::from_millis(2)), 5);
        assert_eq!(update(&mut app, start + period * 100_006 - Duration::from_micros(300)), 1);
    }
}
