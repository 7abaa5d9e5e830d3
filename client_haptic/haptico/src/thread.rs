//! The 1 kHz haptic thread and the handle the game thread steers it with (kira-style: the thread owns
//! the loop; latest values come back through a triple buffer; commands go in and tick timings come out
//! through fixed-capacity ring buffers allocated up front).
//!
//! You need this module to run a device in real time. The hot loop never allocates, frees, locks or logs:
//! delegates bound at run time are boxed on the game thread, and unbound ones are sent back to it to be
//! freed (call [`HapticHandle::collect_garbage`] now and then).

use std::sync::Mutex;
use std::thread::JoinHandle;

use haptic_common::{
    BoxedDelegate, DelegateHandle, DeviceState, ForceOnHapticTick, ForceTorque, OnTransform, PendingDelegate,
};

use crate::core::{HapticCore, HapticEvents};
use crate::timing::{HapticClock, TickTiming, next_deadline, wait_until};
use crate::{Device, HapticoError, Result};

/// Settings of the haptic thread.
#[derive(Clone, Debug, PartialEq)]
pub struct HapticConfig {
    /// Tick rate, Hz (default 1000).
    pub rate_hz: f32,
    /// Spin instead of sleeping for the last part of each period, µs (default 300).
    pub spin_margin_us: u32,
    /// Capacity of the tick-timing ring buffer, ticks (default 65 536: drain it at least every minute).
    pub timing_capacity: usize,
    /// Capacity of the command ring buffer (default 64).
    pub command_capacity: usize,
    /// Room for delegates bound while running, per event (default 16).
    pub delegate_capacity: usize,
    /// Periods a late loop may fall behind and still run every missed tick (default 5); beyond, it
    /// skips them and starts afresh (counted in telemetry).
    pub catch_up_periods: u32,
    /// Real-time FIFO priority for the thread, 1..=99 (default None: normal scheduling). Needs
    /// CAP_SYS_NICE or an rtprio limit; when refused the thread runs normally and telemetry says so.
    pub realtime_priority: Option<i32>,
}

impl Default for HapticConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            spin_margin_us: 300,
            timing_capacity: 1 << 16,
            command_capacity: 64,
            delegate_capacity: 16,
            catch_up_periods: 5,
            realtime_priority: None,
        }
    }
}

/// The latest state of the haptic thread, for the game thread.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HapticTelemetry {
    /// Ticks run so far.
    pub ticks: u64,
    /// The device state of the last tick.
    pub device: DeviceState,
    /// The force and torque commanded on the last tick.
    pub command: ForceTorque,
    /// Ticks skipped because the thread was more than one period late.
    pub skipped_ticks: u64,
    /// Tick timings lost because the timing ring buffer was full.
    pub dropped_timings: u64,
    /// True when the thread got the real-time priority it asked for.
    pub realtime: bool,
}

enum Command {
    Stop,
    SetForcesEnabled(bool),
    BindOnTransform(PendingDelegate<OnTransform>),
    BindForce(PendingDelegate<ForceOnHapticTick>),
    PurgeUnbound,
}

/// Memory handed back by the haptic thread so that the game thread frees it.
#[allow(dead_code)] // held only to be dropped on the game thread
enum Garbage {
    OnTransform(BoxedDelegate<OnTransform>),
    Force(BoxedDelegate<ForceOnHapticTick>),
    RefusedOnTransform(PendingDelegate<OnTransform>),
    RefusedForce(PendingDelegate<ForceOnHapticTick>),
}

/// Everything the haptic thread owns; `run_tick` is one loop iteration minus the wait.
struct ThreadState<D> {
    core: HapticCore<D>,
    commands: rtrb::Consumer<Command>,
    garbage: rtrb::Producer<Garbage>,
    timings: rtrb::Producer<TickTiming>,
    telemetry: triple_buffer::Input<HapticTelemetry>,
    last_start_us: Option<u64>,
    skipped: u64,
    dropped_timings: u64,
    realtime: bool,
}

impl<D: Device> ThreadState<D> {
    /// Runs commands and one tick at `t_us`; returns false when asked to stop. Allocation-free.
    fn run_tick(&mut self, clock: &HapticClock, t_us: u64) -> bool {
        for _ in 0..16 {
            let Ok(command) = self.commands.pop() else { break };
            match command {
                Command::Stop => return false,
                Command::SetForcesEnabled(on) => self.core.set_forces_enabled(on),
                Command::BindOnTransform(p) => {
                    if let Err(p) = self.core.events_mut().on_transform.bind_boxed(p) {
                        let _ = self.garbage.push(Garbage::RefusedOnTransform(p));
                    }
                }
                Command::BindForce(p) => {
                    if let Err(p) = self.core.events_mut().force_on_haptic_tick.bind_boxed(p) {
                        let _ = self.garbage.push(Garbage::RefusedForce(p));
                    }
                }
                Command::PurgeUnbound => {
                    let garbage = &mut self.garbage;
                    let events = self.core.events_mut();
                    // A full garbage ring leaks the box rather than freeing it here.
                    events.on_transform.purge_unbound(|b| {
                        if let Err(rtrb::PushError::Full(g)) = garbage.push(Garbage::OnTransform(b)) {
                            std::mem::forget(g);
                        }
                    });
                    events.force_on_haptic_tick.purge_unbound(|b| {
                        if let Err(rtrb::PushError::Full(g)) = garbage.push(Garbage::Force(b)) {
                            std::mem::forget(g);
                        }
                    });
                }
            }
        }
        self.core.tick(t_us);
        let end_us = clock.now_us().max(t_us);
        let period_us = self.last_start_us.map_or(0, |s| t_us.saturating_sub(s)) as u32;
        self.last_start_us = Some(t_us);
        let timing =
            TickTiming { tick: self.core.ticks() - 1, start_us: t_us, period_us, work_us: (end_us - t_us) as u32 };
        if self.timings.push(timing).is_err() {
            self.dropped_timings += 1;
        }
        self.telemetry.write(HapticTelemetry {
            ticks: self.core.ticks(),
            device: self.core.last_state(),
            command: self.core.last_command(),
            skipped_ticks: self.skipped,
            dropped_timings: self.dropped_timings,
            realtime: self.realtime,
        });
        true
    }
}

struct HandleInner<D> {
    commands: rtrb::Producer<Command>,
    garbage: rtrb::Consumer<Garbage>,
    timings: rtrb::Consumer<TickTiming>,
    telemetry: triple_buffer::Output<HapticTelemetry>,
    join: Option<JoinHandle<D>>,
}

/// Steers a running haptic thread from the game thread (or any other non-real-time thread).
///
/// Dropping the handle stops the thread and releases the device.
pub struct HapticHandle<D: Device + 'static> {
    inner: Mutex<HandleInner<D>>,
    clock: HapticClock,
    config: HapticConfig,
}

impl<D: Device + 'static> std::fmt::Debug for HapticHandle<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HapticHandle").field("config", &self.config).finish_non_exhaustive()
    }
}

/// The command ring buffer is full: the haptic thread is not running or not keeping up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the haptic thread's command queue is full (is it running?)")]
pub struct CommandQueueFull;

impl<D: Device + 'static> HapticHandle<D> {
    /// Starts the haptic thread ticking `device` with `events` at `config.rate_hz`, on `clock`.
    pub fn spawn(device: D, mut events: HapticEvents, config: HapticConfig, clock: HapticClock) -> Result<Self> {
        if !(config.rate_hz > 0.0 && config.rate_hz <= 100_000.0) {
            return Err(HapticoError::InvalidConfig(format!("rate_hz = {}", config.rate_hz)));
        }
        events.on_transform.reserve(config.delegate_capacity);
        events.force_on_haptic_tick.reserve(config.delegate_capacity);
        let (commands_tx, commands_rx) = rtrb::RingBuffer::new(config.command_capacity.max(1));
        let (garbage_tx, garbage_rx) = rtrb::RingBuffer::new(config.command_capacity.max(1) * 2);
        let (timings_tx, timings_rx) = rtrb::RingBuffer::new(config.timing_capacity.max(1));
        let (telemetry_in, telemetry_out) = triple_buffer::triple_buffer(&HapticTelemetry::default());
        let mut state = ThreadState {
            core: HapticCore::new(device, events, config.rate_hz),
            commands: commands_rx,
            garbage: garbage_tx,
            timings: timings_tx,
            telemetry: telemetry_in,
            last_start_us: None,
            skipped: 0,
            dropped_timings: 0,
            realtime: false,
        };
        let priority = config.realtime_priority;
        let catch_up = config.catch_up_periods as u64;
        let period_ns = (1e9 / config.rate_hz as f64) as u64;
        let spin_ns = config.spin_margin_us as u64 * 1000;
        let join = std::thread::Builder::new()
            .name("haptic".into())
            .spawn(move || {
                state.realtime = priority.is_some_and(crate::timing::make_current_thread_realtime);
                let mut deadline = clock.now_ns() + period_ns;
                loop {
                    wait_until(&clock, deadline, spin_ns);
                    if !state.run_tick(&clock, clock.now_us()) {
                        break;
                    }
                    let (next, skipped) = next_deadline(deadline, clock.now_ns(), period_ns, catch_up);
                    deadline = next;
                    state.skipped += skipped;
                }
                state.core.into_device()
            })
            .map_err(HapticoError::Spawn)?;
        Ok(Self {
            inner: Mutex::new(HandleInner {
                commands: commands_tx,
                garbage: garbage_rx,
                timings: timings_rx,
                telemetry: telemetry_out,
                join: Some(join),
            }),
            clock,
            config,
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HandleInner<D>> {
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn send(&self, command: Command) -> std::result::Result<(), CommandQueueFull> {
        self.lock().commands.push(command).map_err(|_| CommandQueueFull)
    }

    /// The clock the thread ticks on.
    pub fn clock(&self) -> HapticClock {
        self.clock
    }

    /// The configuration the thread was started with.
    pub fn config(&self) -> &HapticConfig {
        &self.config
    }

    /// Turns force output on or off (takes effect on the next tick).
    pub fn set_forces_enabled(&self, enabled: bool) -> std::result::Result<(), CommandQueueFull> {
        self.send(Command::SetForcesEnabled(enabled))
    }

    /// Binds a delegate to OnTransform while running (boxed here, bound on the next tick).
    pub fn bind_on_transform(
        &self,
        delegate: impl FnMut(&OnTransform) + Send + 'static,
    ) -> std::result::Result<DelegateHandle, CommandQueueFull> {
        let (pending, handle) = PendingDelegate::new(delegate);
        self.send(Command::BindOnTransform(pending)).map(|_| handle)
    }

    /// Binds a delegate to ForceOnHapticTick while running (called after those bound before).
    pub fn bind_force(
        &self,
        delegate: impl FnMut(&ForceOnHapticTick) + Send + 'static,
    ) -> std::result::Result<DelegateHandle, CommandQueueFull> {
        let (pending, handle) = PendingDelegate::new(delegate);
        self.send(Command::BindForce(pending)).map(|_| handle)
    }

    /// Asks the thread to drop unbound delegates (their memory comes back through `collect_garbage`).
    pub fn purge_unbound(&self) -> std::result::Result<(), CommandQueueFull> {
        self.send(Command::PurgeUnbound)
    }

    /// Frees what the thread handed back (unbound or refused delegates); returns how many items.
    pub fn collect_garbage(&self) -> usize {
        let mut inner = self.lock();
        let mut n = 0;
        while inner.garbage.pop().is_ok() {
            n += 1;
        }
        n
    }

    /// The latest telemetry.
    pub fn telemetry(&self) -> HapticTelemetry {
        *self.lock().telemetry.read()
    }

    /// Moves the tick timings recorded since the last call into `out`; returns how many.
    pub fn drain_timings(&self, out: &mut Vec<TickTiming>) -> usize {
        let mut inner = self.lock();
        let mut n = 0;
        while let Ok(t) = inner.timings.pop() {
            out.push(t);
            n += 1;
        }
        n
    }

    /// True while the thread runs.
    pub fn is_running(&self) -> bool {
        self.lock().join.as_ref().is_some_and(|j| !j.is_finished())
    }

    /// Stops the thread, waits for it, and returns the released device (None if the thread panicked).
    pub fn stop(self) -> Option<D> {
        self.stop_inner()
    }

    fn stop_inner(&self) -> Option<D> {
        let mut inner = self.lock();
        let join = inner.join.take()?;
        // Retry while the queue is full: the thread drains 16 commands per tick.
        while inner.commands.push(Command::Stop).is_err() {
            if join.is_finished() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        drop(inner);
        let device = join.join().ok();
        self.collect_garbage();
        device
    }
}

impl<D: Device + 'static> Drop for HapticHandle<D> {
    fn drop(&mut self) {
        self.stop_inner();
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use glam::Vec3;

    use super::*;
    use crate::sim::{SimConfig, SimDevice, TargetPath};
    use crate::{MockDevice, presets};

    /// Polls `done` every millisecond for up to 10 s (robust on a loaded CI machine).
    fn eventually(mut done: impl FnMut() -> bool) -> bool {
        let start = std::time::Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if done() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        false
    }

    fn thread_state<D: Device>(
        device: D,
        events: HapticEvents,
    ) -> (ThreadState<D>, rtrb::Producer<Command>, rtrb::Consumer<TickTiming>, triple_buffer::Output<HapticTelemetry>)
    {
        let (ctx, crx) = rtrb::RingBuffer::new(8);
        let (gtx, _grx) = rtrb::RingBuffer::new(8);
        let (ttx, trx) = rtrb::RingBuffer::new(4096);
        let (tin, tout) = triple_buffer::triple_buffer(&HapticTelemetry::default());
        let state = ThreadState {
            core: HapticCore::new(device, events, 1000.0),
            commands: crx,
            garbage: gtx,
            timings: ttx,
            telemetry: tin,
            last_start_us: None,
            skipped: 0,
            dropped_timings: 0,
            realtime: false,
        };
        (state, ctx, trx, tout)
    }

    #[test]
    fn a_steady_state_tick_neither_allocates_nor_frees() {
        let device = SimDevice::new(
            SimConfig::new(presets::phantom_premium_6dof()),
            TargetPath::line(Vec3::ZERO, Vec3::new(0.0, -0.01, 0.0), 1.0),
        );
        let mut events = HapticEvents::with_capacity(4);
        let mut sum = Vec3::ZERO;
        events.on_transform.add_delegate(move |s: &OnTransform| sum += s.pose.translation);
        events.force_on_haptic_tick.add_delegate(|t: &ForceOnHapticTick| {
            let y = t.device.pose.translation.y;
            if y < 0.0 {
                t.add(ForceTorque { force: Vec3::Y * (-400.0 * y), torque: Vec3::ZERO });
            }
        });
        let (mut state, mut commands, mut timings, _tout) = thread_state(device, events);
        let clock = HapticClock::new();
        let (pending, handle) = PendingDelegate::new(|t: &ForceOnHapticTick| t.add(ForceTorque::ZERO));
        assert!(commands.push(Command::BindForce(pending)).is_ok());
        assert!(commands.push(Command::SetForcesEnabled(true)).is_ok());
        assert_no_alloc::assert_no_alloc(|| {
            for i in 0..2000u64 {
                assert!(state.run_tick(&clock, i * 1000));
            }
        });
        assert!(handle.is_bound());
        assert_eq!(timings.slots(), 2000);
        assert_eq!(timings.pop().map(|t| t.tick), Ok(0));
    }

    #[test]
    fn the_thread_ticks_within_ten_percent_of_its_rate_over_two_seconds_and_stops_on_request() {
        let (device, log) = MockDevice::touch();
        let clock = HapticClock::new();
        let handle =
            HapticHandle::spawn(device, HapticEvents::default(), HapticConfig::default(), clock).expect("spawn");
        assert!(eventually(|| handle.telemetry().ticks > 0));
        let (t0, ticks0) = (clock.now_us(), handle.telemetry().ticks);
        std::thread::sleep(Duration::from_secs(2));
        let telemetry = handle.telemetry();
        let elapsed_s = (clock.now_us() - t0) as f64 * 1e-6;
        let rate_hz = (telemetry.ticks - ticks0) as f64 / elapsed_s;
        // Each period is either ticked (late ones caught up) or counted as skipped, so ticks and skips
        // together keep time whatever the load; the ticks alone must stay within 10 % of the rate.
        let accounted_hz = (telemetry.ticks + telemetry.skipped_ticks - ticks0) as f64 / elapsed_s;
        assert!((accounted_hz - 1000.0).abs() < 20.0, "ticks + skipped = {accounted_hz:.0} per second");
        assert!((rate_hz - 1000.0).abs() < 100.0, "{rate_hz:.0} Hz (skipped {})", telemetry.skipped_ticks);
        let mut timings = Vec::new();
        handle.drain_timings(&mut timings);
        assert!(timings.len() as u64 >= telemetry.ticks - ticks0);
        assert!(handle.stop().is_some());
        assert_eq!(log.releases(), 1);
    }

    #[test]
    fn delegates_bound_through_the_handle_run_and_come_back_to_be_freed_once_unbound() {
        let (device, log) = MockDevice::touch();
        let handle = HapticHandle::spawn(device, HapticEvents::default(), HapticConfig::default(), HapticClock::new())
            .expect("spawn");
        let d = handle
            .bind_force(|t: &ForceOnHapticTick| t.add(ForceTorque { force: Vec3::X, torque: Vec3::ZERO }))
            .expect("bind");
        assert!(eventually(|| log.last_force() == Vec3::X));
        d.unbind();
        handle.purge_unbound().expect("purge");
        assert!(eventually(|| log.last_force() == Vec3::ZERO));
        let mut freed = 0;
        assert!(eventually(|| {
            freed += handle.collect_garbage();
            freed == 1
        }));
        handle.set_forces_enabled(false).expect("command");
        drop(handle);
        assert_eq!(log.releases(), 1);
    }

    #[test]
    fn an_absurd_rate_is_refused() {
        let (device, _log) = MockDevice::touch();
        let config = HapticConfig { rate_hz: 0.0, ..Default::default() };
        assert!(HapticHandle::spawn(device, HapticEvents::default(), config, HapticClock::new()).is_err());
    }
}
