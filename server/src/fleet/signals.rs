//! SIGTERM and SIGINT: the first starts a drain, the second exits at once.

use bevy::log::{info, warn};
use signal_hook::consts::{SIGINT, SIGTERM};

use super::drain::Drain;

/// Starts the thread that turns termination signals into a drain (the first) or an immediate exit with
/// status 128 + the signal (the second).
pub fn drain_on_termination(drain: Drain) -> std::io::Result<()> {
    let mut signals = signal_hook::iterator::Signals::new([SIGTERM, SIGINT])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        for signal in signals.forever() {
            let name = if signal == SIGTERM { "SIGTERM" } else { "SIGINT" };
            if drain.request() {
                info!("{name}: draining (a second {name} exits at once)");
            } else {
                warn!("second {name}: exiting now, without waiting for the heists");
                std::process::exit(128 + signal);
            }
        }
    })?;
    Ok(())
}
