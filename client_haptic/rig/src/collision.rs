//! The collision thread's settings and pacing: collette's pipeline ([`collette::pipeline`]) is the
//! collision thread; the rig runs it at a fixed rate on the haptic clock (sleep, then spin, catch-up
//! limit, optional real-time priority) and records every step's timing.
//!
//! You need this module to tune the collision thread of a [`HapticRig`](crate::HapticRig).

use std::time::Duration;

use haptico::HapticClock;
use haptico::timing::{make_current_thread_realtime, next_deadline, wait_until};

use crate::spec::{MAX_OBJECTS, MAX_PAIR_WATCHERS};

pub use collette::pipeline::StepTiming;

/// Settings of the collision thread.
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionConfig {
    /// Step rate, Hz (default 1000).
    pub rate_hz: f32,
    /// Time a step's queries may take before the rest is estimated, µs (default 500).
    pub budget_us: u32,
    /// Spin instead of sleeping for the last part of each period, µs (default 300).
    pub spin_margin_us: u32,
    /// Capacity of the step-timing ring buffer (default 65 536).
    pub timing_capacity: usize,
    /// Periods a late loop may fall behind and still run every missed step (default 5).
    pub catch_up_periods: u32,
    /// Real-time FIFO priority, 1..=99 (default None); keep it below the haptic thread's.
    pub realtime_priority: Option<i32>,
    /// Query only the objects whose bounds touch the tool's (default true); false queries every object
    /// every step, for comparison.
    pub broad_phase: bool,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            budget_us: 500,
            spin_margin_us: 300,
            timing_capacity: 1 << 16,
            catch_up_periods: 5,
            realtime_priority: None,
            broad_phase: true,
        }
    }
}

impl CollisionConfig {
    /// Period of a step, ns.
    fn period_ns(&self) -> u64 {
        (1e9 / self.rate_hz.max(1.0) as f64) as u64
    }

    /// collette's settings for these (objects: the tool and [`MAX_OBJECTS`]; watchers: the tool's
    /// against the scene and [`MAX_PAIR_WATCHERS`] between objects; `budget` overrides `budget_us`).
    pub(crate) fn pipeline(&self, budget: Option<Duration>) -> collette::pipeline::CollisionConfig {
        collette::pipeline::CollisionConfig {
            max_objects: MAX_OBJECTS + 1,
            max_watchers: 1 + MAX_PAIR_WATCHERS,
            command_capacity: 1024,
            period: Duration::from_nanos(self.period_ns()),
            step_budget: budget.unwrap_or(Duration::from_micros(self.budget_us as u64)),
            timing_capacity: self.timing_capacity.max(1),
            broad_phase: self.broad_phase,
        }
    }
}

/// Paces collette's collision thread on the haptic clock: sleep, then spin to each deadline.
pub(crate) struct RigPacer {
    pub(crate) clock: HapticClock,
    period_ns: u64,
    spin_ns: u64,
    catch_up: u64,
    priority: Option<i32>,
    deadline_ns: Option<u64>,
}

impl RigPacer {
    pub(crate) fn new(clock: HapticClock, config: &CollisionConfig) -> Self {
        Self {
            clock,
            period_ns: config.period_ns(),
            spin_ns: config.spin_margin_us as u64 * 1000,
            catch_up: config.catch_up_periods as u64,
            priority: config.realtime_priority,
            deadline_ns: None,
        }
    }
}

impl collette::pipeline::Pacer for RigPacer {
    fn start(&mut self) {
        if let Some(priority) = self.priority {
            make_current_thread_realtime(priority);
        }
    }

    fn wait(&mut self) {
        let deadline = match self.deadline_ns {
            Some(d) => next_deadline(d, self.clock.now_ns(), self.period_ns, self.catch_up).0,
            None => self.clock.now_ns() + self.period_ns,
        };
        wait_until(&self.clock, deadline, self.spin_ns);
        self.deadline_ns = Some(deadline);
    }

    fn now_us(&self) -> u64 {
        self.clock.now_us()
    }
}
