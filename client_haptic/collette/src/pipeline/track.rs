//! A moving object's last few poses with the game time of each, read at any time in between: a game
//! that moves an object at 60 Hz gives the 1 kHz threads a pose that moves continuously, not one step
//! per frame, and the velocity the damping needs.
//!
//! You need this module to move objects from a game loop ([`PoseWriter::set_track`]
//! (super::PoseWriter::set_track)), or to read such an object's motion on another thread. The track is
//! read `delay_us` behind the reader's clock, so that the time read lies between two samples the game
//! has already sent (entity interpolation, as networked games draw other players). Past the newest
//! sample the object rests there (or, with `max_extrapolation_us`, goes on with the last segment's
//! velocity for that long first); a sample that comes more than `delay_us` after the newest starts
//! from rest (the newest pose is repeated `delay_us` before it), so a game that stops moving an object,
//! or starts again, or hitches, never makes it jump. Plain `Copy` data: it travels through the
//! lock-free buffers whole.

use glam::{Quat, Vec3};
use haptic_common::Pose;

/// Samples a track keeps (the newest ones).
pub const TRACK_SAMPLES: usize = 4;

/// How a track is read: how far behind the reader's clock, and how far past the newest sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrackTiming {
    /// The track is read this long before now, µs (default 20 000: a little more than a 60 Hz frame,
    /// so that the time read has a sample on each side; a faster game can use less).
    pub delay_us: u32,
    /// Longest extrapolation past the newest sample when the game is late, µs (default 0: the object
    /// rests at its newest pose until the next one comes). After it the object stays where the
    /// extrapolation left it, which is not where the game last put it: use it only with a game that
    /// sends a pose every frame, stops included.
    pub max_extrapolation_us: u32,
}

impl Default for TrackTiming {
    fn default() -> Self {
        Self { delay_us: 20_000, max_extrapolation_us: 0 }
    }
}

/// A pose with the linear velocity of its origin (m/s, world frame) and its angular velocity (rad/s,
/// world frame) at the time it was read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedMotion {
    /// The pose.
    pub pose: Pose,
    /// Velocity of the pose's origin, units/s.
    pub linear_velocity: Vec3,
    /// Angular velocity, rad/s.
    pub angular_velocity: Vec3,
}

impl TrackedMotion {
    /// Velocity of a point fixed to the object, given in world coordinates at this pose, units/s.
    pub fn velocity_at(&self, point: Vec3) -> Vec3 {
        self.linear_velocity + self.angular_velocity.cross(point - self.pose.translation)
    }
}

/// The newest [`TRACK_SAMPLES`] poses of a moving object, oldest first, each with its time (µs on the
/// reader's clock).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseTrack {
    samples: [(Pose, u64); TRACK_SAMPLES],
    len: usize,
    /// How the track is read.
    pub timing: TrackTiming,
}

impl Default for PoseTrack {
    fn default() -> Self {
        Self::new(TrackTiming::default())
    }
}

impl PoseTrack {
    /// An empty track read with `timing`.
    pub fn new(timing: TrackTiming) -> Self {
        Self { samples: [(Pose::IDENTITY, 0); TRACK_SAMPLES], len: 0, timing }
    }

    /// Adds the pose the object had at `t_us`; a sample at the newest sample's time replaces it, an
    /// older one or a pose that is not finite is ignored (returns false). A sample more than
    /// `delay_us` after the newest starts from rest: the newest pose is repeated at `t_us - delay_us`
    /// first (with a delay of 0, the track is read at the newest sample and nothing is repeated).
    pub fn push(&mut self, pose: Pose, t_us: u64) -> bool {
        if !pose.is_finite() {
            return false;
        }
        match self.newest() {
            Some((_, newest)) if t_us < newest => return false,
            Some((_, newest)) if t_us == newest => {
                self.samples[self.len - 1] = (pose, t_us);
                return true;
            }
            Some((resting, newest)) if self.timing.delay_us > 0 && t_us - newest > self.timing.delay_us as u64 => {
                self.append(resting, t_us - self.timing.delay_us as u64);
            }
            _ => {}
        }
        self.append(pose, t_us);
        true
    }

    /// Appends a sample, dropping the oldest when full.
    fn append(&mut self, pose: Pose, t_us: u64) {
        if self.len == TRACK_SAMPLES {
            self.samples.copy_within(1.., 0);
            self.len -= 1;
        }
        self.samples[self.len] = (pose, t_us);
        self.len += 1;
    }

    /// Forgets every sample (keeps the timing).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// The samples, oldest first.
    pub fn samples(&self) -> &[(Pose, u64)] {
        &self.samples[..self.len]
    }

    /// The newest sample.
    pub fn newest(&self) -> Option<(Pose, u64)> {
        self.samples().last().copied()
    }

    /// The object's pose and velocity at `now_us` (read `delay_us` earlier); `None` for an empty track.
    /// Before the oldest sample it rests at that sample; between two it moves along the segment
    /// (translation linearly, rotation along the shortest arc); past the newest it goes on with the last
    /// segment's velocity for at most `max_extrapolation_us`, then rests.
    pub fn at(&self, now_us: u64) -> Option<TrackedMotion> {
        let samples = self.samples();
        let (&(first, t_first), &(last, t_last)) = (samples.first()?, samples.last()?);
        let at_rest = |pose| TrackedMotion { pose, linear_velocity: Vec3::ZERO, angular_velocity: Vec3::ZERO };
        let t = now_us.saturating_sub(self.timing.delay_us as u64);
        if samples.len() == 1 || t <= t_first {
            return Some(at_rest(if t <= t_first { first } else { last }));
        }
        if t >= t_last {
            let (before, t_before) = samples[samples.len() - 2];
            let (v, w) = velocities(&before, &last, (t_last - t_before) as f32 * 1e-6);
            let ahead_us = t - t_last;
            let limit = self.timing.max_extrapolation_us as u64;
            let dt = ahead_us.min(limit) as f32 * 1e-6;
            let pose = Pose { translation: last.translation + v * dt, rotation: advance(last.rotation, w, dt) };
            return Some(if ahead_us >= limit {
                at_rest(pose)
            } else {
                TrackedMotion { pose, linear_velocity: v, angular_velocity: w }
            });
        }
        let i = samples.windows(2).position(|pair| t < pair[1].1)?;
        let ((a, ta), (b, tb)) = (samples[i], samples[i + 1]);
        let span_s = (tb - ta) as f32 * 1e-6;
        let s = (t - ta) as f32 / (tb - ta) as f32;
        let (v, w) = velocities(&a, &b, span_s);
        let pose =
            Pose { translation: a.translation.lerp(b.translation, s), rotation: a.rotation.slerp(b.rotation, s) };
        Some(TrackedMotion { pose, linear_velocity: v, angular_velocity: w })
    }
}

/// Linear and angular velocity that take pose `a` to pose `b` in `span_s` seconds (world frame).
fn velocities(a: &Pose, b: &Pose, span_s: f32) -> (Vec3, Vec3) {
    if span_s <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let mut turn = b.rotation * a.rotation.inverse();
    if turn.w < 0.0 {
        turn = -turn; // the shorter way round
    }
    ((b.translation - a.translation) / span_s, turn.to_scaled_axis() / span_s)
}

/// `rotation` turned by angular velocity `w` for `dt_s` seconds.
fn advance(rotation: Quat, w: Vec3, dt_s: f32) -> Quat {
    (Quat::from_scaled_axis(w * dt_s) * rotation).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TIMING: TrackTiming = TrackTiming { delay_us: 20_000, max_extrapolation_us: 50_000 };

    fn at_x(x: f32) -> Pose {
        Pose::from_translation(Vec3::X * x)
    }

    #[test]
    fn an_object_sent_at_60_hz_moves_smoothly_at_1_khz_with_its_velocity() {
        // 0.5 m/s along x, a pose every 16 667 µs, read every millisecond as the samples arrive.
        let mut track = PoseTrack::new(TIMING);
        let (mut last_x, mut biggest_step) = (None::<f32>, 0.0f32);
        for now_us in (0..400_000u64).step_by(1000) {
            let frame_us = now_us / 16_667 * 16_667;
            track.push(at_x(0.5 * frame_us as f32 * 1e-6), frame_us);
            let motion = track.at(now_us).expect("has samples");
            if now_us >= 40_000 {
                let want = 0.5 * (now_us - 20_000) as f32 * 1e-6;
                assert!((motion.pose.translation.x - want).abs() < 1e-5, "at {now_us}: {motion:?}");
                assert!((motion.linear_velocity.x - 0.5).abs() < 1e-3, "at {now_us}: {motion:?}");
            }
            if let Some(x) = last_x {
                biggest_step = biggest_step.max(motion.pose.translation.x - x);
            }
            last_x = Some(motion.pose.translation.x);
        }
        assert!(biggest_step < 0.000_51, "0.5 mm a millisecond, never a frame's 8.3 mm: {biggest_step}");
    }

    #[test]
    fn a_late_game_is_extrapolated_for_a_while_then_the_object_rests() {
        let mut track = PoseTrack::new(TIMING);
        track.push(at_x(0.0), 0);
        track.push(at_x(0.01), 10_000); // 1 m/s
        let ahead = track.at(40_000).expect("samples"); // read at 20 000: 10 ms past the newest
        assert!((ahead.pose.translation.x - 0.02).abs() < 1e-6, "{ahead:?}");
        assert!((ahead.linear_velocity.x - 1.0).abs() < 1e-4, "{ahead:?}");
        let stopped = track.at(1_000_000).expect("samples");
        assert!((stopped.pose.translation.x - 0.06).abs() < 1e-6, "50 ms of extrapolation at most: {stopped:?}");
        assert_eq!(stopped.linear_velocity, Vec3::ZERO, "then at rest");
        assert_eq!(track.at(5_000).expect("samples").pose, at_x(0.0), "before the oldest: at the oldest");
    }

    #[test]
    fn an_object_the_game_stops_rests_where_it_was_left_and_starts_again_without_a_jump() {
        // Default timing: read 20 ms behind, no extrapolation. 0.5 m/s at 60 Hz until 100 ms, then no
        // pose for 200 ms, then moving again from where it stopped.
        let mut track = PoseTrack::default();
        let mut positions = Vec::new();
        for now_us in (0..600_000u64).step_by(1000) {
            let frame_us = now_us / 16_667 * 16_667;
            let sending = frame_us <= 100_000 || frame_us >= 300_000;
            if sending && now_us % 16_667 < 1000 {
                // Where the game puts it: stopped at its last pose before 100 ms, on from there at 300 ms.
                let moved_us = frame_us.min(83_335) + frame_us.saturating_sub(300_006);
                track.push(at_x(0.5 * moved_us as f32 * 1e-6), frame_us);
            }
            positions.push(track.at(now_us).expect("samples").pose.translation.x);
        }
        let last_sent = 0.5 * 83_335.0 * 1e-6;
        assert!((positions[250] - last_sent).abs() < 1e-6, "at rest where it was last put: {}", positions[250]);
        let biggest = positions.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0f32, f32::max);
        assert!(biggest < 0.001, "no jump when it stops or starts again: {biggest}");
        assert!(positions[599] > 0.1, "and it moved on: {}", positions[599]);
    }

    #[test]
    fn a_turning_object_has_its_angular_velocity_and_points_on_it_their_speed() {
        let mut track = PoseTrack::new(TrackTiming { delay_us: 0, max_extrapolation_us: 0 });
        track.push(Pose::IDENTITY, 0);
        track.push(Pose::new(Vec3::ZERO, Quat::from_rotation_z(0.1)), 100_000); // 1 rad/s about z
        let motion = track.at(50_000).expect("samples");
        assert!((motion.angular_velocity - Vec3::Z).length() < 1e-4, "{motion:?}");
        let rim = motion.pose.transform_point(Vec3::X);
        assert!((motion.velocity_at(rim).length() - 1.0).abs() < 1e-4, "a point 1 m out moves at 1 m/s");
        assert!(motion.pose.rotation.angle_between(Quat::from_rotation_z(0.05)) < 1e-4, "half way round");
    }

    #[test]
    fn old_repeated_and_broken_samples_are_handled() {
        let mut track = PoseTrack::new(TIMING);
        assert!(track.at(0).is_none(), "empty");
        assert!(track.push(at_x(0.0), 100) && track.push(at_x(1.0), 200));
        assert!(!track.push(at_x(9.0), 150), "older than the newest: ignored");
        assert!(!track.push(Pose::from_translation(Vec3::NAN), 300), "not a number: ignored");
        assert!(track.push(at_x(2.0), 200), "the same time: replaces");
        assert_eq!(track.samples(), &[(at_x(0.0), 100), (at_x(2.0), 200)]);
        (3..10).for_each(|i| assert!(track.push(at_x(i as f32), 100 * i)));
        assert_eq!(track.samples().len(), TRACK_SAMPLES, "keeps the newest");
        assert_eq!(track.samples()[0], (at_x(6.0), 600));
        track.clear();
        assert!(track.at(1000).is_none());
    }
}
