//! The three events of the haptic stack (paper §3.3–3.6) and their payloads.
//!
//! You need this module to hook code into the haptic or collision thread: bind a delegate to the
//! [`Delegator`](crate::Delegator) of the event you care about.
//! - [`OnTransform`]: broadcast by the haptic thread after each device read (every tick, ~1 kHz);
//! - [`ForceOnHapticTick`]: broadcast by the haptic thread right after `OnTransform`; delegates add the
//!   force and torque they want on the device, the thread sums them and commands the device;
//! - [`OnCollision`]: broadcast by a collision layer after each collision step, with its contact set.

use std::cell::Cell;

use crate::{ContactSet, DeviceState, ForceTorque};

/// Payload of the OnTransform event: the device sample of this tick.
pub type OnTransform = DeviceState;

/// Payload of the OnCollision event: the contact set of the collision step that just finished.
pub type OnCollision = ContactSet;

/// Payload of the ForceOnHapticTick event: the tick's inputs plus an accumulator delegates add forces to.
///
/// The accumulator is a `Cell`, so delegates receive `&ForceOnHapticTick` and still contribute; the
/// event never leaves the haptic thread (it is not `Sync`).
#[derive(Debug, Default)]
pub struct ForceOnHapticTick {
    /// Index of the haptic tick (0 for the first).
    pub tick: u64,
    /// Time since the previous tick, seconds (the nominal period on the first tick).
    pub dt_s: f32,
    /// The device sample of this tick (the same one broadcast by OnTransform).
    pub device: DeviceState,
    total: Cell<ForceTorque>,
}

impl ForceOnHapticTick {
    /// A tick event with a zero accumulator.
    pub fn new(tick: u64, dt_s: f32, device: DeviceState) -> Self {
        Self { tick, dt_s, device, total: Cell::new(ForceTorque::ZERO) }
    }

    /// Adds a force (N) and torque (N·m) to the tick's total.
    #[inline]
    pub fn add(&self, ft: ForceTorque) {
        let mut t = self.total.get();
        t.force += ft.force;
        t.torque += ft.torque;
        self.total.set(t);
    }

    /// Replaces the tick's total (for a final stage such as a safety layer, bound last).
    #[inline]
    pub fn set(&self, ft: ForceTorque) {
        self.total.set(ft);
    }

    /// The sum of what delegates added so far.
    #[inline]
    pub fn total(&self) -> ForceTorque {
        self.total.get()
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::Delegator;

    #[test]
    fn force_delegates_add_up_and_a_last_stage_can_replace_the_sum() {
        let mut ev = Delegator::<ForceOnHapticTick>::new();
        ev.add_delegate(|t: &ForceOnHapticTick| t.add(ForceTorque { force: Vec3::X, torque: Vec3::ZERO }));
        ev.add_delegate(|t: &ForceOnHapticTick| t.add(ForceTorque { force: Vec3::Y, torque: Vec3::Z }));
        let tick = ForceOnHapticTick::new(0, 0.001, DeviceState::default());
        ev.broadcast(&tick);
        assert_eq!(tick.total(), ForceTorque { force: Vec3::new(1.0, 1.0, 0.0), torque: Vec3::Z });
        ev.add_delegate(|t: &ForceOnHapticTick| t.set(ForceTorque { force: t.total().force * 0.5, ..t.total() }));
        let tick = ForceOnHapticTick::new(1, 0.001, DeviceState::default());
        ev.broadcast(&tick);
        assert_eq!(tick.total().force, Vec3::new(0.5, 0.5, 0.0));
    }
}
