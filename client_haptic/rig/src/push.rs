//! Objects the tool pushes: the haptic thread moves a pushed object at once, the game's rigid body
//! follows through a spring, and what that spring does to the game's body is handed back as impulses.
//!
//! You need this module to let the tool push objects the game simulates ([`HapticRig::add_pushable`]
//! (crate::HapticRig::add_pushable)), and to read what to apply to them
//! ([`HapticRig::take_pushes`](crate::HapticRig::take_pushes)).
//!
//! Why not hand the tool's force straight to the game: the game's body answers it a frame and the
//! track's delay later (40–50 ms at 60 Hz), and a stiff contact against a body that answers late gains
//! energy — a 50 g object would fly off or buzz. Here each pushed object has a *haptic body* on the
//! haptic thread, with the object's mass and inertia: the tool's contact force moves it on the very
//! tick (the collision thread measures the object where it is), and a critically damped spring–damper
//! pulls it towards where the game's body is (its track). The game receives the spring's force on its
//! body, so the game's body follows the haptic body, and the haptic body feels the game's body held
//! back (by a table's friction, a wall) through the same spring. It is the virtual coupling of the
//! device and the tool (Colgate et al. 1995) once more, between the haptic thread and the game's
//! physics. The spring's natural frequency is 1.5 / [`PushCoupling::latency_s`] (33 rad/s for 45 ms):
//! stiff enough that the two bodies stay within a few millimetres while a hand pushes, soft enough that
//! the game's late answer cannot pump energy into it. Over a push the game's body receives the whole
//! impulse the tool gave (the haptic body ends at rest, in step with it).
//!
//! What it cannot do: the haptic body does not collide with the game's other bodies; it feels them
//! only through the spring (a light object pinned against a wall by the tool feels like a spring of
//! `mass · ω²`, 220 N/m for 200 g; a 5 kg one, 5.6 kN/m).

use glam::{Mat3, Quat, Vec3};
use haptic_common::Pose;

use forcecomp::BodyMotion;

/// How pushed objects are coupled to the game's bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PushCoupling {
    /// How long the game takes to show a push in the poses it sends, seconds: the tracks' delay
    /// ([`TrackTiming::delay_us`](crate::TrackTiming)) plus one and a half of its frames (default
    /// 0.045: 20 ms and a 60 Hz game; a 30 Hz game sets 0.070). Larger is softer and safer.
    pub latency_s: f32,
}

impl Default for PushCoupling {
    fn default() -> Self {
        Self { latency_s: 0.045 }
    }
}

impl PushCoupling {
    /// The coupling spring's natural frequency, rad/s.
    pub fn omega_rad_per_s(&self) -> f32 {
        1.5 / self.latency_s.max(1e-3)
    }
}

/// What the tool did to one object the game simulates since the last
/// [`take_pushes`](crate::HapticRig::take_pushes): apply it to the object's rigid body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectPush {
    /// The object's id.
    pub id: u32,
    /// Linear impulse on the body at its centre of mass, scene frame, N·s.
    pub impulse_ns: Vec3,
    /// Angular impulse on the body about its centre of mass, scene frame, N·m·s.
    pub angular_impulse_nms: Vec3,
    /// The haptic ticks it covers: from the first (µs on the rig's clock, the tick before it) ...
    pub from_us: u64,
    /// ... to the last, µs.
    pub to_us: u64,
}

impl ObjectPush {
    /// The mean force over the time it covers, N (zero for no time).
    pub fn mean_force_n(&self) -> Vec3 {
        let s = self.to_us.saturating_sub(self.from_us) as f32 * 1e-6;
        if s > 0.0 { self.impulse_ns / s } else { Vec3::ZERO }
    }

    /// Adds a later push on the same object.
    pub(crate) fn merge(&mut self, later: &ObjectPush) {
        self.impulse_ns += later.impulse_ns;
        self.angular_impulse_nms += later.angular_impulse_nms;
        self.from_us = self.from_us.min(later.from_us);
        self.to_us = self.to_us.max(later.to_us);
    }
}

/// Capacity of the ring of pushes from the haptic thread (one entry a tick per object being pushed;
/// when it is full, pushes wait in their objects and nothing is lost).
pub(crate) const PUSH_RING: usize = 4096;

/// Offsets below which a haptic body that nothing touches is back in step with the game's body.
const IN_STEP_M: f32 = 1e-6;
const IN_STEP_M_PER_S: f32 = 1e-5;
const IN_STEP_RAD: f32 = 1e-5;

/// The haptic thread's copy of a pushed object (lives in its watched object, allocated on the game
/// thread).
pub(crate) struct PushedBody {
    mass_kg: f32,
    /// Inertia about the centre of mass in the object's frame, kg·m².
    inertia: Mat3,
    inverse_inertia: Mat3,
    /// Centre of mass in the object's frame.
    center_of_mass: Vec3,
    /// Where the object's pose goes to the collision thread (the haptic body's, each tick).
    pub(crate) writer: collette::pipeline::PoseWriter,
    /// The haptic body: centre of mass, orientation, velocities (scene frame).
    state: BodyMotion,
    /// Whether it is off the game's body (a contact, or the spring still pulling it back).
    active: bool,
    /// The tool's force and torque (about its centre of mass) on it this tick.
    reaction: (Vec3, Vec3),
    /// Impulses not yet handed to the game.
    pending: ObjectPush,
}

impl PushedBody {
    /// A body of `mass_kg` at uniform density over `tree`'s inner spheres (whose centre of mass, in the
    /// tree's frame, is `center_of_mass`), at `pose`.
    pub(crate) fn new(
        tree: &collette::InnerSphereTree,
        center_of_mass: Vec3,
        mass_kg: f32,
        pose: Pose,
        writer: collette::pipeline::PoseWriter,
        id: u32,
    ) -> Self {
        let inertia = inertia_of(tree, center_of_mass, mass_kg);
        let inverse_inertia = if inertia.determinant() > 0.0 { inertia.inverse() } else { Mat3::ZERO };
        let state =
            BodyMotion { orientation: pose.rotation, ..BodyMotion::at_rest(pose.transform_point(center_of_mass)) };
        Self {
            mass_kg,
            inertia,
            inverse_inertia,
            center_of_mass,
            writer,
            state,
            active: false,
            reaction: (Vec3::ZERO, Vec3::ZERO),
            pending: ObjectPush { id, ..Default::default() },
        }
    }

    /// The haptic body's motion (what the tool touches).
    pub(crate) fn motion(&self) -> BodyMotion {
        self.state
    }

    /// Adds the tool's force and torque about the body's centre of mass this tick.
    pub(crate) fn add_reaction(&mut self, force: Vec3, torque: Vec3) {
        self.reaction.0 += force;
        self.reaction.1 += torque;
        self.active = true;
    }

    /// Puts the haptic body where the game's body is, at rest relative to it.
    pub(crate) fn place(&mut self, game: BodyMotion) {
        self.state = game;
        self.active = false;
    }

    /// One tick of `dt_s` at `now_us`: the tool's reaction and the spring towards the game's body
    /// (`game`) move the haptic body; the spring's impulse on the game's body is kept for it; the new
    /// pose goes to the collision thread.
    pub(crate) fn step(&mut self, game: BodyMotion, coupling: &PushCoupling, dt_s: f32, now_us: u64) {
        let (force, torque) = std::mem::take(&mut self.reaction);
        if !self.active {
            self.place(game);
        } else {
            let w = coupling.omega_rad_per_s();
            let s = &mut self.state;
            // Linear: the spring's acceleration ω²·Δx + 2ω·Δv (critically damped), and the tool's push.
            let spring_accel =
                w * w * (game.center_of_mass - s.center_of_mass) + 2.0 * w * (game.linear_velocity - s.linear_velocity);
            s.linear_velocity += (spring_accel + force / self.mass_kg) * dt_s;
            s.center_of_mass += s.linear_velocity * dt_s;
            // Angular, the same about the centre of mass (the spring scales with the inertia).
            let error = game.orientation * s.orientation.inverse();
            let error = if error.w < 0.0 { -error } else { error };
            let spring_alpha = w * w * 2.0 * Vec3::new(error.x, error.y, error.z)
                + 2.0 * w * (game.angular_velocity - s.angular_velocity);
            let rotation = Mat3::from_quat(s.orientation);
            let world_inverse = rotation * self.inverse_inertia * rotation.transpose();
            let world_inertia = rotation * self.inertia * rotation.transpose();
            s.angular_velocity += (spring_alpha + world_inverse * torque) * dt_s;
            let turn = s.angular_velocity * dt_s;
            s.orientation = (Quat::from_scaled_axis(turn) * s.orientation).normalize();
            // The spring's force and torque on the game's body are the opposite of those on this one.
            let pending = &mut self.pending;
            if pending.impulse_ns == Vec3::ZERO && pending.angular_impulse_nms == Vec3::ZERO {
                pending.from_us = now_us.saturating_sub((dt_s * 1e6) as u64);
            }
            pending.impulse_ns -= spring_accel * self.mass_kg * dt_s;
            pending.angular_impulse_nms -= world_inertia * spring_alpha * dt_s;
            pending.to_us = now_us;
            let in_step = s.center_of_mass.distance(game.center_of_mass) < IN_STEP_M
                && s.linear_velocity.distance(game.linear_velocity) < IN_STEP_M_PER_S
                && s.orientation.angle_between(game.orientation) < IN_STEP_RAD
                && s.angular_velocity.distance(game.angular_velocity) < IN_STEP_RAD
                && force == Vec3::ZERO
                && torque == Vec3::ZERO;
            self.active = !in_step;
        }
        self.writer.set(pose_of(&self.state, self.center_of_mass), now_us);
    }

    /// The impulses kept for the game, if any; cleared once `handed` says they went.
    pub(crate) fn hand_over(&mut self, handed: impl FnOnce(ObjectPush) -> bool) {
        let p = self.pending;
        if (p.impulse_ns != Vec3::ZERO || p.angular_impulse_nms != Vec3::ZERO) && handed(p) {
            self.pending = ObjectPush { id: p.id, ..Default::default() };
        }
    }
}

/// The pose (scene frame) of a body whose centre of mass, at `center_of_mass` in its own frame, moves
/// as `motion` says.
pub(crate) fn pose_of(motion: &BodyMotion, center_of_mass: Vec3) -> Pose {
    Pose::new(motion.center_of_mass - motion.orientation * center_of_mass, motion.orientation)
}

/// Inertia about `center` in the tree's frame of a body of `mass_kg` spread over its inner spheres in
/// proportion to the volume each stands for, kg·m² (each sphere a solid ball).
pub fn inertia_of(tree: &collette::InnerSphereTree, center: Vec3, mass_kg: f32) -> Mat3 {
    let mut inertia = Mat3::ZERO;
    let mut weight = 0.0f32;
    for (s, share) in tree.spheres().iter().zip(tree.weights()) {
        let w = s.radius * s.radius * s.radius * share;
        let r = s.center - center;
        let point = Mat3::from_diagonal(Vec3::splat(r.length_squared())) - outer(r, r);
        let ball = Mat3::from_diagonal(Vec3::splat(0.4 * s.radius * s.radius));
        inertia += (point + ball) * w;
        weight += w;
    }
    if weight > 0.0 { inertia * (mass_kg / weight) } else { Mat3::ZERO }
}

fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packed_ball_has_about_the_inertia_of_a_solid_ball() {
        let (v, t) = collette::shape::uv_sphere_buffers(0.05, 16, 24);
        let mesh = collette::TriMesh::new(v, t).expect("mesh");
        let (tree, _) = collette::build(&mesh, &collette::BuildOptions::spheres(800), &mut |_| {}).expect("tree");
        let c = crate::spec::center_of_mass(&tree);
        let i = inertia_of(&tree, c, 2.0);
        let solid = 0.4 * 2.0 * 0.05 * 0.05;
        for k in 0..3 {
            let d = i.col(k)[k];
            assert!((d - solid).abs() < 0.15 * solid, "axis {k}: {d} kg·m², a solid ball {solid}");
        }
        assert!(i.col(0)[1].abs() < 0.05 * solid, "no product of inertia: {}", i.col(0)[1]);
    }

    #[test]
    fn merged_pushes_add_their_impulses_and_span_both_times() {
        let mut a = ObjectPush { id: 1, impulse_ns: Vec3::X, angular_impulse_nms: Vec3::Y, from_us: 10, to_us: 20 };
        a.merge(&ObjectPush { id: 1, impulse_ns: Vec3::X, angular_impulse_nms: Vec3::ZERO, from_us: 20, to_us: 30 });
        assert_eq!((a.impulse_ns, a.from_us, a.to_us), (Vec3::X * 2.0, 10, 30));
        assert!((a.mean_force_n() - Vec3::X * 1e5).length() < 1.0);
    }
}
