//! One haptic tick without the clock: read the device, broadcast OnTransform, gather forces through
//! ForceOnHapticTick, command the device. The haptic thread calls it at 1 kHz; tests call it directly.
//!
//! You need this module to drive a device at your own pace (for example inside a simulation loop), or to
//! test force delegates deterministically.

use haptic_common::{Delegator, DeviceState, ForceOnHapticTick, ForceTorque, OnTransform};

use crate::device::Device;

/// The two events the haptic thread broadcasts each tick.
#[derive(Debug)]
pub struct HapticEvents {
    /// Broadcast after each device read, with the device state.
    pub on_transform: Delegator<OnTransform>,
    /// Broadcast after OnTransform; delegates add the force and torque to command.
    pub force_on_haptic_tick: Delegator<ForceOnHapticTick>,
}

impl Default for HapticEvents {
    fn default() -> Self {
        Self::with_capacity(16)
    }
}

impl HapticEvents {
    /// Events with room for `capacity` delegates each (delegates bound later through the handle do not allocate).
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            on_transform: Delegator::with_capacity(capacity),
            force_on_haptic_tick: Delegator::with_capacity(capacity),
        }
    }
}

/// The device plus its events, ticked with explicit times.
#[derive(Debug)]
pub struct HapticCore<D> {
    device: D,
    events: HapticEvents,
    tick: u64,
    last_t_us: Option<u64>,
    nominal_dt_s: f32,
    forces_enabled: bool,
    last_state: DeviceState,
    last_command: ForceTorque,
}

impl<D: Device> HapticCore<D> {
    /// A core ticking `device` at a nominal `rate_hz` (used as dt on the first tick).
    pub fn new(device: D, events: HapticEvents, rate_hz: f32) -> Self {
        Self {
            device,
            events,
            tick: 0,
            last_t_us: None,
            nominal_dt_s: 1.0 / rate_hz.max(1.0),
            forces_enabled: true,
            last_state: DeviceState::default(),
            last_command: ForceTorque::ZERO,
        }
    }

    /// Runs one tick at time `t_us` on the haptic clock and returns the force commanded. No allocation,
    /// no lock (as long as the device and the delegates have none).
    pub fn tick(&mut self, t_us: u64) -> ForceTorque {
        let dt_s = match self.last_t_us {
            Some(last) => t_us.saturating_sub(last) as f32 * 1e-6,
            None => self.nominal_dt_s,
        };
        self.last_t_us = Some(t_us);
        let state = self.device.read_state(t_us);
        self.events.on_transform.broadcast(&state);
        let event = ForceOnHapticTick::new(self.tick, dt_s, state);
        self.events.force_on_haptic_tick.broadcast(&event);
        let command = if self.forces_enabled { self.device.specs().clamp(event.total()) } else { ForceTorque::ZERO };
        self.device.command(command);
        self.tick += 1;
        self.last_state = state;
        self.last_command = command;
        command
    }

    /// Turns force output on or off (off commands zero every tick; reading goes on).
    pub fn set_forces_enabled(&mut self, enabled: bool) {
        self.forces_enabled = enabled;
    }

    /// Ticks run so far.
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// The device state read on the last tick.
    pub fn last_state(&self) -> DeviceState {
        self.last_state
    }

    /// The force and torque commanded on the last tick.
    pub fn last_command(&self) -> ForceTorque {
        self.last_command
    }

    /// The events, to bind or purge delegates while the core is not running in a thread.
    pub fn events_mut(&mut self) -> &mut HapticEvents {
        &mut self.events
    }

    /// The device.
    pub fn device(&self) -> &D {
        &self.device
    }

    /// The device, mutably.
    pub fn device_mut(&mut self) -> &mut D {
        &mut self.device
    }

    /// Releases the device (zero force) and gives it back.
    pub fn into_device(mut self) -> D {
        self.device.release();
        self.device
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::MockDevice;

    #[test]
    fn a_tick_reads_then_broadcasts_then_commands_the_summed_and_clamped_force() {
        let (dev, log) = MockDevice::touch();
        let mut events = HapticEvents::default();
        let seen = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let s = seen.clone();
        events
            .on_transform
            .add_delegate(move |st: &OnTransform| s.store(st.timestamp_us, std::sync::atomic::Ordering::Relaxed));
        events.force_on_haptic_tick.add_delegate(|t: &ForceOnHapticTick| {
            t.add(ForceTorque { force: Vec3::new(2.0, 0.0, 0.0), torque: Vec3::ZERO })
        });
        events.force_on_haptic_tick.add_delegate(|t: &ForceOnHapticTick| {
            t.add(ForceTorque { force: Vec3::new(2.0, 0.0, 0.0), torque: Vec3::ZERO })
        });
        let mut core = HapticCore::new(dev, events, 1000.0);
        let f = core.tick(1234);
        assert_eq!(seen.load(std::sync::atomic::Ordering::Relaxed), 1234);
        assert!((f.force.x - 3.3).abs() < 1e-5, "4 N requested, Touch peak is 3.3 N");
        assert_eq!(log.reads(), 1);
        assert!((log.last_force().x - 3.3).abs() < 1e-5);
    }

    #[test]
    fn dt_is_the_time_between_ticks_and_nominal_on_the_first() {
        let (dev, _log) = MockDevice::touch();
        let mut events = HapticEvents::default();
        let dts = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let d = dts.clone();
        events.force_on_haptic_tick.add_delegate(move |t: &ForceOnHapticTick| d.lock().expect("lock").push(t.dt_s));
        let mut core = HapticCore::new(dev, events, 1000.0);
        core.tick(0);
        core.tick(1500);
        let dts = dts.lock().expect("lock").clone();
        assert_eq!(dts.len(), 2);
        assert!((dts[0] - 0.001).abs() < 1e-9 && (dts[1] - 0.0015).abs() < 1e-9);
    }

    #[test]
    fn disabled_forces_command_zero() {
        let (dev, log) = MockDevice::touch();
        let mut events = HapticEvents::default();
        events
            .force_on_haptic_tick
            .add_delegate(|t: &ForceOnHapticTick| t.add(ForceTorque { force: Vec3::ONE, torque: Vec3::ZERO }));
        let mut core = HapticCore::new(dev, events, 1000.0);
        core.set_forces_enabled(false);
        assert_eq!(core.tick(0), ForceTorque::ZERO);
        assert_eq!(log.last_force(), Vec3::ZERO);
    }
}
