//! A device whose I/O blocks (a USB round trip, a request to a local service) on a thread of its own,
//! so the haptic thread never waits for it.
//!
//! You need this module to put a real device under the haptic thread: [`IoDevice::spawn`] runs the
//! device's own `read_state`/`command` in a loop on an I/O thread, as fast as the device answers (at
//! most `rate_hz`), and the haptic thread exchanges only the latest values with it — the newest state
//! through one triple buffer, the newest force through another — so neither blocks, allocates or locks.
//! A state is stamped with when the I/O thread read it, moved onto the haptic thread's clock: its
//! timestamp is the tick's time less its age, so a device that stopped answering shows as stale.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

use haptic_common::{DeviceState, ForceTorque};

use crate::timing::{HapticClock, next_deadline, wait_until};
use crate::{Device, DeviceSpecs, HapticoError, Result};

/// Counters of the I/O thread, readable from any thread.
#[derive(Debug, Default)]
pub struct IoStats {
    exchanges: AtomicU64,
}

impl IoStats {
    /// Read-and-command rounds the I/O thread has done.
    pub fn exchanges(&self) -> u64 {
        self.exchanges.load(Ordering::Relaxed)
    }
}

/// The I/O thread's side: where it writes states and finds the newest force (see [`IoDevice::with_loop`]).
pub struct IoThread {
    /// Each state read, stamped on [`Self::clock`].
    pub states: triple_buffer::Input<DeviceState>,
    forces: triple_buffer::Output<ForceTorque>,
    /// Counters; the loop counts each exchange in `exchanges`.
    pub stats: Arc<IoStats>,
    stop: Arc<AtomicBool>,
    /// The haptic side's clock.
    pub clock: HapticClock,
}

impl IoThread {
    /// The newest force the haptic thread commanded.
    pub fn newest_force(&mut self) -> ForceTorque {
        *self.forces.read()
    }

    /// True once the haptic side let go: the loop leaves the device without force and returns.
    pub fn stopping(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// Counts one exchange.
    pub fn count_exchange(&self) {
        self.stats.exchanges.fetch_add(1, Ordering::Relaxed);
    }
}

/// The haptic thread's side of a device run on an I/O thread.
pub struct IoDevice {
    specs: DeviceSpecs,
    states: triple_buffer::Output<DeviceState>,
    forces: triple_buffer::Input<ForceTorque>,
    stats: Arc<IoStats>,
    clock: HapticClock,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl IoDevice {
    /// Starts an I/O thread named `name` running `device` at most `rate_hz` rounds a second. The device
    /// is released when this is dropped.
    pub fn spawn<D: Device + 'static>(mut device: D, rate_hz: f32, name: &str) -> Result<Self> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(HapticoError::InvalidConfig(format!("I/O rate {rate_hz} Hz")));
        }
        let specs = device.specs().clone();
        let clock = HapticClock::new();
        let first = device.read_state(clock.now_us());
        let period_ns = (1e9 / f64::from(rate_hz)) as u64;
        Self::with_loop(specs, first, clock, name, move |mut io: IoThread| {
            let mut deadline = io.clock.now_ns();
            while !io.stopping() {
                io.states.write(device.read_state(io.clock.now_us()));
                device.command(io.newest_force());
                io.count_exchange();
                (deadline, _) = next_deadline(deadline, io.clock.now_ns(), period_ns, 5);
                wait_until(&io.clock, deadline, 200_000);
            }
            device.release();
        })
    }

    /// Starts an I/O thread named `name` running `body`, which owns the device's I/O: it writes each state
    /// it reads (stamped on `clock`) and sends the newest force, counting its exchanges, until
    /// [`IoThread::stopping`]. `first` is the state read before the thread starts.
    pub fn with_loop(
        specs: DeviceSpecs,
        first: DeviceState,
        clock: HapticClock,
        name: &str,
        body: impl FnOnce(IoThread) + Send + 'static,
    ) -> Result<Self> {
        let (states_in, states) = triple_buffer::triple_buffer(&first);
        let (forces, forces_out) = triple_buffer::triple_buffer(&ForceTorque::ZERO);
        let stats = Arc::new(IoStats::default());
        let stop = Arc::new(AtomicBool::new(false));
        let io = IoThread { states: states_in, forces: forces_out, stats: stats.clone(), stop: stop.clone(), clock };
        let thread =
            std::thread::Builder::new().name(name.to_owned()).spawn(move || body(io)).map_err(HapticoError::Spawn)?;
        Ok(Self { specs, states, forces, stats, clock, stop, thread: Some(thread) })
    }

    /// The I/O thread's counters.
    pub fn stats(&self) -> Arc<IoStats> {
        self.stats.clone()
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Device for IoDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    /// The newest state the I/O thread read, stamped `t_us` less its age.
    #[inline]
    fn read_state(&mut self, t_us: u64) -> DeviceState {
        let state = *self.states.read();
        let age = self.clock.now_us().saturating_sub(state.timestamp_us);
        DeviceState { timestamp_us: t_us.saturating_sub(age), ..state }
    }

    /// Hands the force to the I/O thread, which sends it on its next round.
    fn command(&mut self, ft: ForceTorque) {
        self.forces.write(ft);
    }

    fn release(&mut self) {
        self.forces.write(ForceTorque::ZERO);
        self.stop();
    }
}

impl Drop for IoDevice {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;
    use std::time::Duration;

    use glam::Vec3;
    use haptic_common::Pose;

    use super::*;
    use crate::presets;

    /// A device that takes `delay` to answer each read (a slow USB round trip) and remembers what it
    /// was commanded and whether it was released.
    struct Slow {
        delay: Duration,
        reads: u64,
        log: Arc<Mutex<(Vec<ForceTorque>, bool)>>,
    }

    impl Device for Slow {
        fn specs(&self) -> &DeviceSpecs {
            static SPECS: std::sync::OnceLock<DeviceSpecs> = std::sync::OnceLock::new();
            SPECS.get_or_init(presets::falcon)
        }
        fn read_state(&mut self, t_us: u64) -> DeviceState {
            std::thread::sleep(self.delay);
            self.reads += 1;
            DeviceState {
                pose: Pose::from_translation(Vec3::X * self.reads as f32),
                timestamp_us: t_us,
                ..Default::default()
            }
        }
        fn command(&mut self, ft: ForceTorque) {
            self.log.lock().expect("log").0.push(ft);
        }
        fn release(&mut self) {
            self.log.lock().expect("log").1 = true;
        }
    }

    #[test]
    fn a_device_slower_than_a_tick_never_holds_the_haptic_thread_up() {
        let log = Arc::new(Mutex::new((Vec::new(), false)));
        let slow = Slow { delay: Duration::from_millis(5), reads: 0, log: log.clone() };
        let clock = HapticClock::new();
        let mut io = IoDevice::spawn(slow, 1000.0, "slow-io").expect("spawns");
        // 1,000 haptic-side reads and commands: had each waited for the device, it would have answered
        // 1,000 times meanwhile; it answers every 5 ms.
        let before = io.stats().exchanges();
        let mut latest = DeviceState::default();
        for i in 0..1000 {
            latest = io.read_state(clock.now_us());
            io.command(ForceTorque { force: Vec3::Y * (i as f32 / 1000.0), torque: Vec3::ZERO });
        }
        let answered = io.stats().exchanges() - before;
        assert!(answered < 100, "the device answered {answered} times during 1,000 reads");
        std::thread::sleep(Duration::from_millis(60));
        let newer = io.read_state(clock.now_us());
        assert!(newer.pose.translation.x > latest.pose.translation.x, "the I/O thread kept reading");
        // Read about 5 ms (one answer) before: its timestamp is that much before the tick's.
        let now = clock.now_us() + 1_000_000;
        let stamped = io.read_state(now).timestamp_us;
        assert!(stamped <= now && now - stamped < 100_000, "{} µs old", now - stamped);
        io.release();
        let (commands, released) = &*log.lock().expect("log");
        assert!(*released, "the device is released when the haptic side lets go");
        // The device got the newest force (not every one: at its own pace), then none when let go.
        assert!(commands.iter().any(|c| (c.force.y - 0.999).abs() < 1e-6), "the last force commanded reached it");
        assert!(commands.len() < 200, "at its own pace: {} rounds", commands.len());
        assert_eq!(commands.last().map(|c| c.force), Some(Vec3::ZERO));
    }

    #[test]
    fn a_fast_device_is_run_at_most_at_the_rate_asked() {
        let log = Arc::new(Mutex::new((Vec::new(), false)));
        let fast = Slow { delay: Duration::ZERO, reads: 0, log };
        let io = IoDevice::spawn(fast, 500.0, "fast-io").expect("spawns");
        std::thread::sleep(Duration::from_millis(400));
        // Never faster than asked (plus the five periods a late loop may catch up on).
        let n = io.stats().exchanges();
        assert!(n > 0 && n <= 206, "{n} rounds in 0.4 s at 500 Hz");
        assert!(IoDevice::spawn(Slow { delay: Duration::ZERO, reads: 0, log: Arc::default() }, 0.0, "x").is_err());
    }
}
