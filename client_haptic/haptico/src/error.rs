//! Errors of the device layer. The haptic thread's hot path returns none of them.

use std::path::PathBuf;

/// What can go wrong when opening devices, reading traces or starting the haptic thread.
#[derive(Debug, thiserror::Error)]
pub enum HapticoError {
    /// No device of the wanted kind is connected (a message for people, not an error storm).
    #[error("no {wanted} found; {hint}")]
    NoDevice {
        /// What was looked for, e.g. "3Dconnexion SpaceMouse".
        wanted: String,
        /// What to check (cable, udev rule, permissions).
        hint: String,
    },
    /// The HID layer refused (permissions, device gone, bad report).
    #[error("HID: {0}")]
    Hid(String),
    /// A USB device refused or failed (permissions, device gone, no answer).
    #[error("USB: {0}")]
    Usb(String),
    /// Reading or writing a trace file failed.
    #[error("trace file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A trace file is not in the documented format.
    #[error("trace line {line}: {reason}")]
    TraceFormat {
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        reason: String,
    },
    /// A trace holds no sample.
    #[error("the trace holds no sample")]
    EmptyTrace,
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// The operating system refused to start the haptic thread.
    #[error("cannot start the haptic thread: {0}")]
    Spawn(std::io::Error),
}

/// `Result` with [`HapticoError`].
pub type Result<T, E = HapticoError> = std::result::Result<T, E>;
