//! Compile-time check that the rig's handle can be shared across threads.

use haptic_rig::HapticRig;
use haptico::sim::SimDevice;

fn send_sync<T: Send + Sync>() {}

#[test]
fn the_rig_handle_is_send_and_sync() {
    send_sync::<HapticRig<SimDevice>>();
    send_sync::<HapticRig<Box<dyn haptico::Device>>>();
}
