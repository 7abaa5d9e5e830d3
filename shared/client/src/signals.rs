//! SIGINT and SIGTERM end a client gently: the app exits on its next frame, so its audio engine is
//! dropped and a recording (`--wav`) is written whole, and the seat's ticket stays for a restart; a
//! second signal ends the process at once (exit code 130).
//!
//! You need this module to change how a client stops from outside. Both clients call [`install`] first
//! thing and add [`SignalsPlugin`]; code that waits outside the app (a spoken prompt) asks
//! [`stop_requested`].

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;

fn flag() -> &'static Arc<AtomicBool> {
    static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            // The second signal exits at once (registered first: it checks the flag before it is set).
            let _ = signal_hook::flag::register_conditional_shutdown(signal, 130, flag.clone());
            let _ = signal_hook::flag::register(signal, flag.clone());
        }
        flag
    })
}

/// Installs the handlers (call early in `main`).
pub fn install() {
    flag();
}

/// True once SIGINT or SIGTERM arrived.
pub fn stop_requested() -> bool {
    flag().load(Ordering::Relaxed)
}

/// Exits the app when a signal arrived.
pub struct SignalsPlugin;

impl Plugin for SignalsPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Last, exit_on_signal);
    }
}

fn exit_on_signal(mut exit: MessageWriter<AppExit>, mut done: Local<bool>) {
    if stop_requested() && !*done {
        *done = true;
        info!("stopping: asked to by a signal");
        exit.write(AppExit::Success);
    }
}
