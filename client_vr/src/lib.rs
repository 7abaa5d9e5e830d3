//! The Vive client: join a heist as the sighted player, in a headset through OpenXR or on a desktop.
//!
//! The tree: [`client`] (the game logic every mode shares: session, prediction, interpolation, events),
//! [`intent`] (game-level intents and what they are about), [`predict`] and [`interp`] (the body's
//! prediction and reconciliation; smooth motion for the rest), the inputs — [`xr`] (headset and
//! controllers, and the probe that decides whether XR can run), [`desktop`] (keyboard and mouse),
//! [`bot`] (the Vive bot's brain) — and the presentation: [`world`] (the museum, dressed from [`palette`]'s shared meshes and materials; thrown items fly along [`flight`]'s arcs), [`hud`], [`sound`], and [`walkie`] (the walkie-talkie to Phantom).
//! [`cli`] assembles them into one app per mode (headless, desktop, XR).
#![warn(missing_docs)]
// Bevy queries with filters are long by nature.
#![allow(clippy::type_complexity)]

pub mod bot;
pub mod cli;
pub mod client;
pub mod desktop;
pub mod figure;
pub mod flight;
pub mod hud;
pub mod intent;
pub mod interp;
pub mod museum;
pub mod palette;
pub mod predict;
pub mod sound;
pub mod space;
pub mod state;
pub mod textures;
pub mod walkie;
pub mod world;
pub mod xr;

pub use client::{ViveClientPlugin, ViveSettings, ViveState};
pub use intent::{Action, InputSource, Intent};
