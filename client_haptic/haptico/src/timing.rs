//! The haptic clock, the precise tick scheduler (sleep, then spin) and tick timing statistics.
//!
//! You need this module to run your own fixed-rate loop, or to summarize the tick timings the haptic
//! thread records.

use std::time::{Duration, Instant};

/// A monotonic clock shared by the haptic and collision threads: microseconds since its epoch.
#[derive(Clone, Copy, Debug)]
pub struct HapticClock {
    epoch: Instant,
}

impl Default for HapticClock {
    fn default() -> Self {
        Self::new()
    }
}

impl HapticClock {
    /// A clock whose zero is now.
    pub fn new() -> Self {
        Self { epoch: Instant::now() }
    }

    /// Nanoseconds since the epoch.
    #[inline]
    pub fn now_ns(&self) -> u64 {
        self.epoch.elapsed().as_nanos() as u64
    }

    /// Microseconds since the epoch.
    #[inline]
    pub fn now_us(&self) -> u64 {
        self.now_ns() / 1000
    }
}

/// What a fixed-rate loop should do now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wait {
    /// Sleep this long (the deadline is further away than the spin margin).
    Sleep(Duration),
    /// Busy-wait: the deadline is within the spin margin.
    Spin,
    /// The deadline has passed: run the tick.
    Go,
}

/// Decides between sleeping and spinning before `deadline_ns`; pure, so it is tested without a clock.
#[inline]
pub fn plan_wait(now_ns: u64, deadline_ns: u64, spin_margin_ns: u64) -> Wait {
    if now_ns >= deadline_ns {
        Wait::Go
    } else if deadline_ns - now_ns > spin_margin_ns {
        Wait::Sleep(Duration::from_nanos(deadline_ns - now_ns - spin_margin_ns))
    } else {
        Wait::Spin
    }
}

/// The deadline after `deadline_ns` for a loop of `period_ns`. A loop that fell behind by at most
/// `catch_up` periods runs its missed ticks back to back (so short hiccups cost no ticks, only jitter);
/// one further behind starts afresh from `now_ns`. Returns (deadline, ticks skipped).
#[inline]
pub fn next_deadline(deadline_ns: u64, now_ns: u64, period_ns: u64, catch_up: u64) -> (u64, u64) {
    let next = deadline_ns + period_ns;
    if now_ns > next + period_ns * catch_up.max(1) {
        let skipped = (now_ns - next) / period_ns;
        (now_ns + period_ns, skipped)
    } else {
        (next, 0)
    }
}

/// Sleeps, then spins, until `deadline_ns` on `clock`.
pub fn wait_until(clock: &HapticClock, deadline_ns: u64, spin_margin_ns: u64) {
    loop {
        match plan_wait(clock.now_ns(), deadline_ns, spin_margin_ns) {
            Wait::Go => return,
            Wait::Spin => std::hint::spin_loop(),
            Wait::Sleep(d) => std::thread::sleep(d),
        }
    }
}

/// Asks the OS to run the calling thread under a real-time FIFO policy at `priority` (1..=99) and to
/// wake it from sleeps with 1 µs timer slack. Returns false when refused (no privilege, not Linux):
/// the thread then runs as before. Call it once at the start of a real-time thread.
pub fn make_current_thread_realtime(priority: i32) -> bool {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param { sched_priority: priority.clamp(1, 99) };
        // SAFETY: plain system calls on the calling thread (id 0) with a valid, initialized argument.
        let ok = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } == 0;
        // SAFETY: PR_SET_TIMERSLACK takes one integer argument (nanoseconds).
        unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong) };
        ok
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = priority;
        false
    }
}

/// Locks the process's current and future memory in RAM (`mlockall`), so real-time threads never wait
/// on a page fault. Returns false when refused. Call it early in a benchmark or real-time program.
pub fn lock_memory() -> bool {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: plain system call with constant flags.
        unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) == 0 }
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

/// Timing of one haptic tick (recorded into a preallocated ring buffer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TickTiming {
    /// Index of the tick.
    pub tick: u64,
    /// Start of the tick on the haptic clock, µs.
    pub start_us: u64,
    /// Time since the previous tick's start, µs (0 for the first tick).
    pub period_us: u32,
    /// Time spent in the tick (read, events, command), µs.
    pub work_us: u32,
}

/// Percentile `p` (0..=100) of `sorted` (ascending), nearest rank; 0 for an empty slice.
pub fn percentile(sorted: &[u32], p: f64) -> u32 {
    if sorted.is_empty() {
        return 0;
    }
    let rank = ((p / 100.0) * (sorted.len() - 1) as f64).round() as usize;
    sorted[rank.min(sorted.len() - 1)]
}

/// Summary of a run of tick timings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimingSummary {
    /// Ticks summarized.
    pub ticks: usize,
    /// Median period, µs.
    pub period_p50_us: u32,
    /// Median absolute deviation of the period from nominal (jitter), µs.
    pub jitter_p50_us: u32,
    /// 99th percentile of the absolute period deviation, µs.
    pub jitter_p99_us: u32,
    /// Largest absolute period deviation, µs.
    pub jitter_max_us: u32,
    /// 99th percentile of the work per tick, µs.
    pub work_p99_us: u32,
}

/// Summarizes `timings` against a nominal period of `nominal_us` (allocates: not for the hot thread).
pub fn summarize(timings: &[TickTiming], nominal_us: u32) -> TimingSummary {
    let mut periods: Vec<u32> = timings.iter().filter(|t| t.period_us > 0).map(|t| t.period_us).collect();
    let mut jitter: Vec<u32> = periods.iter().map(|p| p.abs_diff(nominal_us)).collect();
    let mut work: Vec<u32> = timings.iter().map(|t| t.work_us).collect();
    periods.sort_unstable();
    jitter.sort_unstable();
    work.sort_unstable();
    TimingSummary {
        ticks: timings.len(),
        period_p50_us: percentile(&periods, 50.0),
        jitter_p50_us: percentile(&jitter, 50.0),
        jitter_p99_us: percentile(&jitter, 99.0),
        jitter_max_us: jitter.last().copied().unwrap_or(0),
        work_p99_us: percentile(&work, 99.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_deadlines_sleep_near_ones_spin_past_ones_go() {
        assert_eq!(plan_wait(0, 1_000_000, 200_000), Wait::Sleep(Duration::from_nanos(800_000)));
        assert_eq!(plan_wait(900_000, 1_000_000, 200_000), Wait::Spin);
        assert_eq!(plan_wait(1_000_001, 1_000_000, 200_000), Wait::Go);
    }

    #[test]
    fn deadlines_advance_by_one_period_and_a_long_stall_resynchronizes() {
        assert_eq!(next_deadline(1_000, 1_500, 1_000, 1), (2_000, 0));
        assert_eq!(next_deadline(1_000, 2_100, 1_000, 1), (2_000, 0));
        let (d, skipped) = next_deadline(1_000, 10_500, 1_000, 1);
        assert_eq!((d, skipped), (11_500, 8));
    }

    #[test]
    fn a_short_hiccup_is_caught_up_instead_of_skipped() {
        assert_eq!(next_deadline(1_000, 5_500, 1_000, 5), (2_000, 0));
        assert_eq!(next_deadline(1_000, 20_500, 1_000, 5).1, 18);
    }

    #[test]
    fn summary_reports_jitter_as_distance_from_the_nominal_period() {
        let t: Vec<TickTiming> = [1000, 1010, 990, 1000, 1300]
            .iter()
            .enumerate()
            .map(|(i, &p)| TickTiming { tick: i as u64, period_us: p, ..Default::default() })
            .collect();
        let s = summarize(&t, 1000);
        assert_eq!(s.period_p50_us, 1000);
        assert_eq!(s.jitter_p50_us, 10);
        assert_eq!(s.jitter_max_us, 300);
    }
}
