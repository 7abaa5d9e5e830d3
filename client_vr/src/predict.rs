//! Client-side prediction of Vive's own movement, reconciled with the authoritative server.
//!
//! Every movement intent the client sends carries a sequence number. The client moves its body at once
//! with the same rule the server uses
//! ([`WallSet::move_body`](heist_shared::level::WallSet::move_body)) and keeps the inputs the server has
//! not yet acknowledged. When a server state arrives (position after input `ack`), the prediction restarts from
//! it and replays the unacknowledged inputs. What the replay changes is the prediction error; it is
//! hidden by a visual offset that decays over [`SMOOTHING_S`] instead of a jump, unless it is larger
//! than [`SNAP_DISTANCE_M`] (a teleport, a catch), which snaps.

use std::collections::VecDeque;

use glam::Vec2;
use heist_shared::level::WallSet;

/// Inputs kept while unacknowledged: 4 s at 60 Hz; older ones are dropped (the server has long moved on).
pub const MAX_PENDING: usize = 240;
/// Time constant of the visual correction, seconds.
pub const SMOOTHING_S: f32 = 0.1;
/// Corrections larger than this snap instead of gliding, metres.
pub const SNAP_DISTANCE_M: f32 = 2.0;

/// One movement input, as sent to the server.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Input {
    /// Its sequence number.
    pub seq: u32,
    /// Direction on the floor, |d| ≤ 1.
    pub direction: Vec2,
    /// Speed, m/s.
    pub speed: f32,
    /// Duration it moved the body for, seconds.
    pub dt: f32,
    /// Where the prediction put the body after it.
    pub predicted: Vec2,
}

/// The predictor (see the module docs).
#[derive(Clone, Debug)]
pub struct Predictor {
    walls: WallSet,
    position: Vec2,
    pending: VecDeque<Input>,
    last_ack: Option<u32>,
    offset: Vec2,
    /// Prediction errors measured at each acknowledgement (the predicted position for input `ack`
    /// against the server's), metres; the latest [`MAX_PENDING`] of them.
    pub errors: VecDeque<f32>,
    /// Corrections that snapped.
    pub snaps: u32,
    /// Acknowledged inputs whose error was measured, since the start.
    pub acked: u32,
    /// The largest error measured since the start, metres.
    pub max_error: f32,
}

impl Predictor {
    /// A predictor for a body at `position` in a museum with `walls`.
    pub fn new(walls: WallSet, position: Vec2) -> Self {
        Self {
            walls,
            position,
            pending: VecDeque::with_capacity(MAX_PENDING),
            last_ack: None,
            offset: Vec2::ZERO,
            errors: VecDeque::with_capacity(MAX_PENDING),
            snaps: 0,
            acked: 0,
            max_error: 0.0,
        }
    }

    /// The predicted (authoritative-to-be) position.
    pub fn position(&self) -> Vec2 {
        self.position
    }

    /// Where to draw the body: the prediction plus the decaying correction.
    pub fn shown(&self) -> Vec2 {
        self.position + self.offset
    }

    /// Inputs not yet acknowledged.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Applies a new input locally (call when it is sent).
    pub fn apply(&mut self, seq: u32, direction: Vec2, speed: f32, dt: f32) {
        self.position = self.walls.move_body(self.position, direction, speed, dt);
        if self.pending.len() == MAX_PENDING {
            self.pending.pop_front();
        }
        self.pending.push_back(Input { seq, direction, speed, dt, predicted: self.position });
    }

    /// Lets the visual correction decay for `dt` seconds.
    pub fn settle(&mut self, dt: f32) {
        self.offset *= (-dt / SMOOTHING_S).exp();
        if self.offset.length_squared() < 1e-8 {
            self.offset = Vec2::ZERO;
        }
    }

    /// Reconciles with a server state: the body is at `server` after input `ack`. Returns the prediction
    /// error for that input (None when it was not pending any more, or the state is not newer).
    pub fn reconcile(&mut self, server: Vec2, ack: u32) -> Option<f32> {
        if self.last_ack.is_some_and(|last| ack < last) {
            return None;
        }
        self.last_ack = Some(ack);
        let mut error = None;
        while let Some(front) = self.pending.front() {
            if front.seq > ack {
                break;
            }
            if front.seq == ack {
                error = Some(front.predicted.distance(server));
            }
            self.pending.pop_front();
        }
        // Replay what the server has not seen yet on top of its state.
        let before = self.shown();
        let mut p = server;
        for input in self.pending.iter_mut() {
            p = self.walls.move_body(p, input.direction, input.speed, input.dt);
            input.predicted = p;
        }
        self.position = p;
        let jump = before - p;
        if jump.length() > SNAP_DISTANCE_M {
            self.offset = Vec2::ZERO;
            self.snaps += 1;
        } else {
            self.offset = jump;
        }
        if let Some(e) = error {
            if self.errors.len() == MAX_PENDING {
                self.errors.pop_front();
            }
            self.errors.push_back(e);
            self.acked += 1;
            self.max_error = self.max_error.max(e);
        }
        error
    }

    /// Puts the body at `position` with nothing pending (joining, or the server moved it).
    pub fn reset(&mut self, position: Vec2) {
        self.position = position;
        self.pending.clear();
        self.offset = Vec2::ZERO;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::level::Level;
    use heist_shared::rules;

    fn open_room() -> (WallSet, Vec2) {
        let level = Level::museum();
        let spawn = level.vive_spawn;
        (WallSet::new(&level), spawn)
    }

    /// A server that applies each input one tick after it arrives, and reports its state `delay`
    /// ticks later — the same rule, so the error must be zero.
    #[test]
    fn with_a_delayed_server_applying_every_input_the_prediction_error_is_zero() {
        let (walls, spawn) = open_room();
        let mut client = Predictor::new(walls.clone(), spawn);
        let mut server = spawn;
        let delay = 9; // 150 ms at 60 Hz
        let mut in_flight: VecDeque<(u32, Vec2, u32)> = VecDeque::new(); // (arrives at tick, pos, ack)
        let dt = 1.0 / 60.0;
        for tick in 0..600u32 {
            let angle = tick as f32 * 0.01;
            let dir = Vec2::new(angle.cos(), angle.sin());
            client.apply(tick + 1, dir, rules::WALK_SPEED, dt);
            server = walls.move_body(server, dir, rules::WALK_SPEED, dt);
            in_flight.push_back((tick + delay, server, tick + 1));
            while in_flight.front().is_some_and(|m| m.0 <= tick) {
                let (_, pos, ack) = in_flight.pop_front().expect("a state is due");
                let e = client.reconcile(pos, ack).expect("the input was pending");
                assert!(e < 1e-5, "error {e} at tick {tick}");
            }
            assert!(client.pending() <= delay as usize + 1);
        }
        assert!(client.position().distance(spawn) > 0.5, "the body moved");
    }

    #[test]
    fn a_server_that_disagrees_is_followed_and_the_correction_glides() {
        let (walls, spawn) = open_room();
        let mut client = Predictor::new(walls, spawn);
        let dt = 1.0 / 60.0;
        for seq in 1..=10 {
            client.apply(seq, Vec2::X, rules::WALK_SPEED, dt);
        }
        // The server says the body stood still until input 5 (say, its first inputs were lost).
        let e = client.reconcile(spawn, 5).expect("input 5 was pending");
        assert!((e - 5.0 * rules::WALK_SPEED * dt).abs() < 1e-4);
        let expected = spawn + Vec2::X * 5.0 * rules::WALK_SPEED * dt;
        assert!(client.position().distance(expected) < 1e-4, "replayed inputs 6..=10");
        assert!(client.shown().distance(client.position()) > 0.1, "shown with the correction offset");
        client.settle(0.5);
        assert!(client.shown().distance(client.position()) < 0.01, "the offset decays");
        // An older state never rewinds the prediction.
        assert_eq!(client.reconcile(spawn, 3), None);
    }

    #[test]
    fn a_far_correction_snaps() {
        let (walls, spawn) = open_room();
        let mut client = Predictor::new(walls, spawn);
        client.apply(1, Vec2::X, rules::WALK_SPEED, 1.0 / 60.0);
        client.reconcile(spawn + Vec2::new(0.0, 5.0), 1);
        assert_eq!(client.snaps, 1);
        assert_eq!(client.shown(), client.position());
    }

    #[test]
    fn the_pending_buffer_is_bounded() {
        let (walls, spawn) = open_room();
        let mut client = Predictor::new(walls, spawn);
        for seq in 1..=1000 {
            client.apply(seq, Vec2::ZERO, 0.0, 1.0 / 60.0);
        }
        assert_eq!(client.pending(), MAX_PENDING);
    }
}
