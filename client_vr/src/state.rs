//! What the Vive client knows of the session: the level and its walls, the predicted body, the phase,
//! the clock and the alarm, what is carried, the HUD's messages and the pulses played.

use bevy::prelude::*;
use glam::Vec2;
use heist_shared::level::{Level, WallSet};
use heist_shared::protocol::Phase;

use crate::predict::Predictor;

/// Why a controller pulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PulseReason {
    /// An item came into the hand.
    Grab,
    /// Glass broke within reach.
    Glass,
}

/// The client's view of the session.
#[derive(Resource, Default)]
pub struct ViveState {
    /// The level, once the server sent it.
    pub level: Option<Level>,
    /// Its walls.
    pub walls: Option<WallSet>,
    /// The body's prediction (after the level arrives).
    pub predictor: Option<Predictor>,
    /// The session phase.
    pub phase: Phase,
    /// Seconds left.
    pub time_left_s: f32,
    /// Alarm level.
    pub alarm: u8,
    /// Items carried (server's word).
    pub carrying: Vec<heist_shared::protocol::ItemId>,
    /// Recent messages for the HUD (time, text), newest last.
    pub feed: Vec<(f64, String)>,
    /// Seconds since the heist ended.
    pub ended_s: f32,
    /// Pulses played (or counted), by reason.
    pub pulses: Vec<PulseReason>,
    /// Server states reconciled.
    pub reconciliations: u32,
    /// When this client hosts: where Phantom joins and with which code (shown in the lobby).
    pub hosted: Option<String>,
}

impl ViveState {
    /// Whether the heist is on (movement is sent and predicted only then).
    pub fn in_heist(&self) -> bool {
        self.phase == Phase::Heist && self.predictor.is_some()
    }

    /// Where the body is drawn (prediction plus smoothing).
    pub fn body(&self) -> Option<Vec2> {
        self.predictor.as_ref().map(Predictor::shown)
    }

    /// Adds a line to the HUD's messages.
    pub fn say(&mut self, now: f64, text: String) {
        info!("{text}");
        if self.feed.len() >= 64 {
            self.feed.drain(..32);
        }
        self.feed.push((now, text));
    }
}
