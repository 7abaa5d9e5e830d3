//! You need this crate to move the game's datagrams between a UDP socket and renet without trusting a
//! single byte of them: it runs netcode (renetcode) and renet as bevy_renet's netcode transport does, but
//! checks every datagram's header before netcode parses it ([`datagram`]), every decrypted renet packet
//! before renet parses it ([`payload`]), and limits the rate of both ([`limit`]). renetcode 2.0.0 and
//! renet 2.0.1 panic on packets these checks refuse (docs/decisions.md has the four reports). A frame's
//! renet packets travel together: one datagram carries all that fit ([`bundle`]).
//!
//! No Bevy and no socket of their own: [`ServerIntake`] and [`ClientIntake`] take datagrams and a send
//! function, so the game (through [`socket`]), the tests and the fuzz target drive the same code.
#![warn(missing_docs)]

pub mod bundle;
pub mod client;
pub mod datagram;
mod error;
pub mod limit;
#[cfg(feature = "test-support")]
pub mod memory;
pub mod payload;
pub mod server;
pub mod socket;
pub mod throttle;

pub use client::ClientIntake;
pub use datagram::DatagramRefusal;
pub use error::{PayloadRefusal, TransportError};
pub use server::{Departure, IntakeLimits, IntakeStats, Refused, ServerIntake};

pub use renet;
pub use renetcode;
