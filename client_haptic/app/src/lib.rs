//! The Phantom client: join a heist as the blind player and play by touch and sound alone.
#![warn(missing_docs)]

pub mod device;
pub mod error;
pub mod explore;
pub mod haptics;
pub mod audio;
pub mod speech;

pub use error::ClientError;
