//! Compile-time check that what crosses threads is Send (+ Sync for handles).

use haptico::sim::SimDevice;
use haptico::trace::TraceDevice;
use haptico::{HapticClock, HapticEvents, HapticHandle, MockDevice};

fn send<T: Send>() {}
fn send_sync<T: Send + Sync>() {}

#[test]
fn handles_are_send_and_sync_and_devices_are_send() {
    send_sync::<HapticHandle<SimDevice>>();
    send_sync::<HapticHandle<Box<dyn haptico::Device>>>();
    send_sync::<HapticClock>();
    send::<HapticEvents>();
    send::<SimDevice>();
    send::<TraceDevice>();
    send::<MockDevice>();
}
