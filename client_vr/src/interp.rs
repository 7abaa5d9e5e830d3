//! Smooth motion for what the server moves (guards, the Phantom's tool): snapshot interpolation.
//!
//! Each replicated update is stamped with the client's clock when it arrives; the world is drawn
//! [`DELAY_S`] in the past, between the two snapshots around that moment, so a guard glides at 60 fps
//! even when updates arrive unevenly or some are lost. Past the newest snapshot it holds still (no
//! extrapolation through walls).

use std::collections::VecDeque;

use bevy::prelude::*;
use glam::{Quat, Vec3};

/// How far in the past the interpolated world is drawn, seconds (three server ticks and some jitter).
pub const DELAY_S: f64 = 0.1;
/// Snapshots kept per object.
pub const CAPACITY: usize = 32;

/// One pose at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Snapshot {
    /// Client time of arrival, seconds.
    pub t: f64,
    /// Position, metres.
    pub position: Vec3,
    /// Orientation.
    pub rotation: Quat,
}

/// The snapshots of one object, oldest first.
#[derive(Component, Clone, Debug, Default)]
pub struct Track {
    snapshots: VecDeque<Snapshot>,
}

impl Track {
    /// Adds a snapshot (ignored when it is not newer than the last).
    pub fn push(&mut self, s: Snapshot) {
        if self.snapshots.back().is_some_and(|last| s.t <= last.t) {
            return;
        }
        if self.snapshots.len() == CAPACITY {
            self.snapshots.pop_front();
        }
        self.snapshots.push_back(s);
    }

    /// Snapshots kept.
    pub fn len(&self) -> usize {
        self.snapshots.len()
    }

    /// Whether no snapshot has arrived.
    pub fn is_empty(&self) -> bool {
        self.snapshots.is_empty()
    }

    /// The newest snapshot.
    pub fn latest(&self) -> Option<&Snapshot> {
        self.snapshots.back()
    }

    /// The pose at client time `t` (use `now - DELAY_S`).
    pub fn sample(&self, t: f64) -> Option<(Vec3, Quat)> {
        let first = self.snapshots.front()?;
        if t <= first.t {
            return Some((first.position, first.rotation));
        }
        for pair in self.snapshots.iter().zip(self.snapshots.iter().skip(1)) {
            let (a, b) = pair;
            if t <= b.t {
                let f = ((t - a.t) / (b.t - a.t)) as f32;
                return Some((a.position.lerp(b.position, f), a.rotation.slerp(b.rotation, f)));
            }
        }
        self.snapshots.back().map(|s| (s.position, s.rotation))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64, x: f32) -> Snapshot {
        Snapshot { t, position: Vec3::new(x, 0.0, 0.0), rotation: Quat::from_rotation_y(x) }
    }

    #[test]
    fn between_snapshots_the_pose_is_blended() {
        let mut track = Track::default();
        track.push(at(1.0, 0.0));
        track.push(at(1.1, 1.0));
        track.push(at(1.3, 3.0));
        let (p, _) = track.sample(1.05).expect("a pose");
        assert!((p.x - 0.5).abs() < 1e-5);
        let (p, r) = track.sample(1.2).expect("a pose");
        assert!((p.x - 2.0).abs() < 1e-5);
        assert!(r.angle_between(Quat::from_rotation_y(2.0)) < 1e-3);
    }

    #[test]
    fn outside_the_buffer_the_pose_holds() {
        let mut track = Track::default();
        assert!(track.sample(0.0).is_none());
        track.push(at(1.0, 0.0));
        track.push(at(2.0, 1.0));
        assert_eq!(track.sample(0.5).expect("a pose").0.x, 0.0);
        assert_eq!(track.sample(9.0).expect("a pose").0.x, 1.0);
    }

    #[test]
    fn a_late_or_duplicate_snapshot_is_ignored_and_the_buffer_is_bounded() {
        let mut track = Track::default();
        track.push(at(2.0, 2.0));
        track.push(at(1.0, 1.0));
        assert_eq!(track.latest().expect("a snapshot").t, 2.0);
        for i in 0..100 {
            track.push(at(3.0 + f64::from(i), 0.0));
        }
        assert_eq!(track.snapshots.len(), CAPACITY);
    }

    /// A guard walking at constant speed, updated unevenly with losses, is drawn at constant speed.
    #[test]
    fn uneven_updates_still_give_even_motion() {
        let mut track = Track::default();
        let arrivals = [0.0, 0.016, 0.05, 0.051, 0.1, 0.117, 0.2, 0.21, 0.25, 0.3, 0.33];
        for &t in &arrivals {
            track.push(at(t, t as f32 * 1.6));
        }
        let mut last = track.sample(0.1).expect("a pose").0.x;
        for i in 1..=10 {
            let t = 0.1 + f64::from(i) * 0.02;
            let x = track.sample(t).expect("a pose").0.x;
            let v = (x - last) / 0.02;
            assert!((v - 1.6).abs() < 0.05, "speed {v} at {t}");
            last = x;
        }
    }
}
