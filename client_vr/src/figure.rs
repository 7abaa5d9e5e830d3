//! A guard drawn as a person: a low-poly figure whose legs and arms swing in a walk or run cycle matched
//! to how fast he is drawn moving, whose body turns the way he walks, and whose head — with his torch —
//! turns the way he looks (the server's facing). A guard searching a room stands still and sweeps his
//! head and light; a guard walking one way while looking another shows it.
//!
//! The cycle is driven by distance, not time: one full cycle (two steps) per [`stride_m`] travelled, so
//! the feet never slide whatever the speed, and the swing widens from a stroll to a run.

use std::f32::consts::{PI, TAU};

use bevy::prelude::*;
use glam::Vec2;

use crate::space;

/// Height of the hip joints, metres.
pub const HIP_M: f32 = 0.9;
/// Height of the shoulder joints, metres.
pub const SHOULDER_M: f32 = 1.42;
/// Height of the neck joint (the head turns about it), metres.
pub const NECK_M: f32 = 1.5;
/// How far the head turns from the body either way, radians (75°); past that the body turns too.
pub const MAX_HEAD_TURN: f32 = 1.3;
/// How fast the body turns towards where he walks (or looks, standing), radians per second.
pub const BODY_TURN_RATE: f32 = 6.0;
/// Below this drawn speed a guard stands (his body turns to his look), m/s.
pub const STANDING_SPEED: f32 = 0.3;
/// Time constant of the drawn speed's smoothing, seconds.
pub const SPEED_SMOOTHING_S: f32 = 0.15;

/// Distance of one full walk cycle (two steps) at `speed` m/s: longer strides when running.
pub fn stride_m(speed: f32) -> f32 {
    1.0 + 0.35 * speed
}

/// Peak swing of a leg from the vertical at `speed` m/s, radians: none standing, about 20° at a patrol's
/// 1.1 m/s, about 45° at a chase's 2.6 m/s.
pub fn swing(speed: f32) -> f32 {
    (0.3 * speed).min(0.8)
}

/// A swinging limb: a leg swings with its side's phase, an arm against its own side's leg.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Limb {
    /// An arm (else a leg).
    pub arm: bool,
    /// +1 left, −1 right.
    pub side: f32,
}

impl Limb {
    /// The limb's angle about the hip or shoulder (positive swings forward), radians.
    pub fn angle(self, phase: f32, speed: f32) -> f32 {
        let leg = self.side * swing(speed) * phase.sin();
        if self.arm { -0.8 * leg } else { leg }
    }
}

/// The neck joint: the head, its nose and the torch turn with it.
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct Neck;

/// A guard's walk as drawn: his smoothed speed, where in the cycle his legs are and which way his body faces.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct Gait {
    /// Phase of the walk cycle, radians in [0, 2π).
    pub phase: f32,
    /// Smoothed drawn speed, m/s.
    pub speed: f32,
    /// Which way the body faces, floor angle (radians from +x, counter-clockwise).
    pub body: f32,
    last: Option<Vec2>,
}

/// `a` wrapped to (−π, π].
fn wrapped(a: f32) -> f32 {
    let a = a.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

impl Gait {
    /// Moves the gait on by one frame of `dt` seconds in which the guard was drawn at floor point `at`
    /// looking along floor angle `look`.
    pub fn step(&mut self, at: Vec2, look: f32, dt: f32) {
        let Some(last) = self.last.replace(at) else {
            self.body = look;
            return;
        };
        if dt <= 0.0 {
            return;
        }
        let moved = at - last;
        let distance = moved.length();
        let speed = distance / dt;
        self.speed += (speed - self.speed) * (1.0 - (-dt / SPEED_SMOOTHING_S).exp());
        self.phase = (self.phase + distance / stride_m(self.speed.max(speed)) * TAU).rem_euclid(TAU);
        let towards = if speed > STANDING_SPEED { moved.y.atan2(moved.x) } else { look };
        let turn = wrapped(towards - self.body);
        self.body = wrapped(self.body + turn.clamp(-BODY_TURN_RATE * dt, BODY_TURN_RATE * dt));
    }

    /// How far the head turns from the body to look along `look`, radians (+ to his left), within
    /// ±[`MAX_HEAD_TURN`].
    pub fn head_turn(&self, look: f32) -> f32 {
        wrapped(look - self.body).clamp(-MAX_HEAD_TURN, MAX_HEAD_TURN)
    }
}

/// The figure's parts under a guard's root entity (which is placed at his feet and turned with his body).
pub struct Parts<'a> {
    /// Torso, with its material.
    pub torso: (&'a Handle<Mesh>, &'a Handle<StandardMaterial>),
    /// A leg or an arm hangs from its joint, with the uniform's material.
    pub leg: &'a Handle<Mesh>,
    /// An arm.
    pub arm: &'a Handle<Mesh>,
    /// The head and the nose (which shows where he looks), with the skin's material.
    pub head: (&'a Handle<Mesh>, &'a Handle<Mesh>, &'a Handle<StandardMaterial>),
}

/// Spawns the figure's torso, limbs and neck under `guard`; returns the neck, for what turns with the head.
pub fn spawn(guard: &mut ChildSpawnerCommands, parts: &Parts) -> Entity {
    let (torso, uniform) = parts.torso;
    guard.spawn((Mesh3d(torso.clone()), MeshMaterial3d(uniform.clone()), Transform::from_xyz(0.0, 1.17, 0.0)));
    for side in [1.0, -1.0] {
        for (arm, mesh, joint, hang) in [
            (false, parts.leg, Vec3::new(-0.1 * side, HIP_M, 0.0), 0.45),
            (true, parts.arm, Vec3::new(-0.26 * side, SHOULDER_M, 0.0), 0.33),
        ] {
            guard.spawn((Limb { arm, side }, Transform::from_translation(joint), Visibility::default())).with_child((
                Mesh3d(mesh.clone()),
                MeshMaterial3d(uniform.clone()),
                Transform::from_xyz(0.0, -hang, 0.0),
            ));
        }
    }
    let (head, nose, skin) = parts.head;
    guard
        .spawn((Neck, Transform::from_xyz(0.0, NECK_M, 0.0), Visibility::default()))
        .with_children(|neck| {
            // A positive turn about +y takes the nose (−z) to the left (−x).
            neck.spawn((Mesh3d(head.clone()), MeshMaterial3d(skin.clone()), Transform::from_xyz(0.0, 0.14, 0.0)));
            neck.spawn((Mesh3d(nose.clone()), MeshMaterial3d(skin.clone()), Transform::from_xyz(0.0, 0.14, -0.15)));
        })
        .id()
}

/// Turns a guard's root, limbs and neck for this frame: the root faces his body's way, each limb at its
/// angle in the cycle, the neck at his head's turn.
pub fn pose(
    gait: &Gait,
    look: f32,
    root: &mut Transform,
    children: &[Entity],
    limbs: &mut Query<(&Limb, &mut Transform), (Without<Neck>, Without<Gait>)>,
    necks: &mut Query<&mut Transform, (With<Neck>, Without<Limb>, Without<Gait>)>,
) {
    root.rotation = space::rotation(gait.body);
    for child in children {
        if let Ok((limb, mut t)) = limbs.get_mut(*child) {
            // A positive turn about +x takes a hanging foot (−y) towards −z, Bevy's forward.
            t.rotation = Quat::from_rotation_x(limb.angle(gait.phase, gait.speed));
        } else if let Ok(mut t) = necks.get_mut(*child) {
            t.rotation = Quat::from_rotation_y(gait.head_turn(look));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(gait: &mut Gait, from: Vec2, velocity: Vec2, look: f32, seconds: f32) -> Vec<(f32, f32)> {
        let dt = 1.0 / 60.0;
        let frames = (seconds / dt) as usize;
        let mut angles = Vec::new();
        for i in 0..=frames {
            gait.step(from + velocity * (i as f32 * dt), look, dt);
            angles.push((Limb { arm: false, side: 1.0 }.angle(gait.phase, gait.speed), gait.phase));
        }
        angles
    }

    #[test]
    fn legs_swing_wider_and_faster_as_the_guard_speeds_up_and_stop_when_he_stands() {
        let mut peak_and_cycles = Vec::new();
        for speed in [1.1, 2.6] {
            let mut gait = Gait::default();
            let angles = walk(&mut gait, Vec2::ZERO, Vec2::new(speed, 0.0), 0.0, 4.0);
            let settled = &angles[60..]; // after the speed's smoothing
            let peak = settled.iter().map(|(a, _)| a.abs()).fold(0.0, f32::max);
            let wraps = settled.windows(2).filter(|w| w[1].1 < w[0].1).count();
            // The feet keep to the floor: one cycle per stride travelled.
            let expected = 3.0 * speed / stride_m(speed);
            assert!(
                (wraps as f32 - expected).abs() <= 1.0,
                "{speed} m/s: {wraps} cycles in 3 s, {expected:.1} expected"
            );
            assert!((peak - swing(speed)).abs() < 0.02, "{speed} m/s: swing {peak}");
            peak_and_cycles.push((peak, wraps));
            // Standing: the swing dies away within a second.
            let here = Vec2::new(speed * 4.0 + speed / 60.0, 0.0);
            let still = walk(&mut gait, here, Vec2::ZERO, 0.0, 1.0);
            let last = still.last().expect("frames").0;
            assert!(last.abs() < 0.01, "standing, the leg hangs: {last}");
        }
        let (walking, running) = (peak_and_cycles[0], peak_and_cycles[1]);
        assert!(running.0 > 2.0 * walking.0, "a run swings wider: {running:?} against {walking:?}");
        assert!(running.1 > walking.1, "and steps faster: {running:?} against {walking:?}");
        assert!((0.3..0.4).contains(&walking.0) && (0.75..0.85).contains(&running.0), "about 20° walking, 45° running");
    }

    #[test]
    fn legs_and_arms_swing_against_each_other() {
        for phase in [0.3f32, 1.2, 2.0, 4.0, 5.5] {
            let l = |arm, side| Limb { arm, side }.angle(phase, 1.4);
            assert!((l(false, 1.0) + l(false, -1.0)).abs() < 1e-6, "the legs are opposite");
            assert!(l(false, 1.0) * l(true, 1.0) < 0.0, "an arm swings against its own side's leg");
            assert!((l(true, 1.0) - 0.8 * l(false, -1.0)).abs() < 1e-6, "with the other leg");
        }
    }

    #[test]
    fn the_body_turns_the_way_he_walks_and_the_head_the_way_he_looks() {
        let mut gait = Gait::default();
        // Walking east while looking north: the body goes east, the head turns 75° to his left (the most it can).
        walk(&mut gait, Vec2::ZERO, Vec2::new(1.1, 0.0), PI / 2.0, 2.0);
        assert!(gait.body.abs() < 1e-3, "the body faces where he walks: {}", gait.body);
        assert!((gait.head_turn(PI / 2.0) - MAX_HEAD_TURN).abs() < 1e-6);
        // Looking 40° right of his way: the head turns exactly that.
        assert!((gait.head_turn(-0.7) + 0.7).abs() < 1e-6);
        // Standing, looking back west: the body comes round to the look, no faster than it can turn,
        // the short way, and then the head is straight.
        let here = Vec2::new(1.1 * 2.0, 0.0);
        let turned = walk(&mut gait, here, Vec2::ZERO, PI, 1.0);
        assert!(turned.len() > 50);
        assert!((wrapped(gait.body - PI)).abs() < 1e-3, "the body faces the look: {}", gait.body);
        assert!(gait.head_turn(PI).abs() < 1e-3);
        let mut slow = Gait::default();
        slow.step(Vec2::ZERO, 0.0, 1.0 / 60.0);
        slow.step(Vec2::ZERO, 3.0, 1.0 / 60.0);
        assert!(
            (slow.body - BODY_TURN_RATE / 60.0).abs() < 1e-5,
            "one frame turns {} rad at most",
            BODY_TURN_RATE / 60.0
        );
    }
}
