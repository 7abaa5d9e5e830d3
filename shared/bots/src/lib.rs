//! Headless bots that play Phantom Heist through the real client core, for tests, the demo and CI.
//!
//! [`ViveBotPlugin`] sneaks, breaks cases and carries copies; [`PhantomBotPlugin`] judges each copy from
//! the geometry it receives and the briefing — never from a label. Both only read what their client
//! receives (replicated components and [`heist_client::Inbox`]) and only write `ClientMsg`s.
#![warn(missing_docs)]

mod forecast;
mod phantom;
mod rounds;
mod spacetime;
mod vive;

pub use phantom::{PhantomBotPlugin, PhantomBrain};
pub use rounds::Rounds;
pub use vive::{Seen, Sight, Turn, ViveBotPlugin, ViveBrain, ViveStyle};
