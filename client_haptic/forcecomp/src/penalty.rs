//! The volumetric penalty force of the paper (Eq. 1) and its torque (Eq. 2), from an Inner Sphere Tree
//! contact set.
//!
//! You need this module for 6-DOF rendering of a tool against an object:
//!
//! F_A = Σ n_ij · max(vol_ij · (ε_c − vel_ij · ε_d / Vol_total), 0)
//! τ_A = Σ (C_ij − A_m) × F_Ai
//!
//! `vel_ij` is the relative velocity of A with respect to B at the collision centre along `n_ij`
//! (negative while A moves deeper), so the damping term strengthens the force on the way in and softens
//! it on the way out; a pair never pulls. Friction adds a regularized Coulomb force opposing the
//! tangential slip, `μ · |F_Ai|`. A material's [`Texture`](crate::Texture) makes the contact patch's
//! push that of a ridged surface at its centre of pressure (and friction follows it). When a time-budgeted query estimated part of the volume without
//! listing its pairs, the force is scaled by `total_volume / listed volume` (at most ×4).

use glam::Vec3;
use haptic_common::{Contact, ContactSet, ForceTorque};

use crate::{BodyMotion, Material};

/// Largest scale applied for volume a budgeted query estimated but did not list.
pub const MAX_ESTIMATE_SCALE: f32 = 4.0;

/// Slip speed below which friction fades out linearly (avoids chatter at rest), m/s.
pub const FRICTION_REGULARIZATION_M_PER_S: f32 = 1e-3;

/// The force and torque on the tool A (about its centre of mass) from `contacts` with object B.
///
/// Contacts with a non-finite field or a non-positive volume are skipped, and non-finite motion counts
/// as rest, so the result is always finite. Allocation-free.
pub fn volumetric_penalty(
    contacts: &ContactSet,
    tool: &BodyMotion,
    object: &BodyMotion,
    material: &Material,
) -> ForceTorque {
    volumetric_penalty_of(contacts.as_slice(), contacts.total_volume, tool, object, material)
}

/// [`volumetric_penalty`] of a slice of contacts whose query measured `total_volume` (e.g. one object's
/// share of a scene watcher's contacts).
pub fn volumetric_penalty_of(
    contacts: &[Contact],
    total_volume: f32,
    tool: &BodyMotion,
    object: &BodyMotion,
    material: &Material,
) -> ForceTorque {
    let valid = |c: &&Contact| {
        c.point.is_finite() && c.normal.is_finite() && c.volume.is_finite() && c.volume > 0.0 && c.normal != Vec3::ZERO
    };
    let listed: f32 = contacts.iter().filter(valid).map(|c| c.volume).sum();
    if !(listed > 0.0 && listed.is_finite()) {
        return ForceTorque::ZERO;
    }
    let tool = if tool.is_finite() { *tool } else { BodyMotion::at_rest(sanitize(tool.center_of_mass)) };
    let object = if object.is_finite() { *object } else { BodyMotion::at_rest(sanitize(object.center_of_mass)) };
    let eps_c = material.stiffness_n_per_m3.max(0.0);
    let eps_d = material.damping_ns_per_m.max(0.0);
    let mu = material.friction.max(0.0);
    // The normal push of pair `c` and the relative velocity it was computed from.
    let push = |c: &Contact| {
        let n = c.normal.try_normalize()?;
        let v_rel = tool.velocity_at(c.point) - object.velocity_at(c.point);
        let magnitude = (c.volume * (eps_c - v_rel.dot(n) * eps_d / listed)).max(0.0);
        Some((n, v_rel, magnitude))
    };
    // With a texture, the contact patch is pressed as one: its push (the sum of the pairs') acts at
    // its centre of pressure, where the ridge height scales every pair's push (and so their friction)
    // and the ridge's slope adds a push along the surface (`Texture::apply`).
    let mut scale_push = 1.0;
    let mut ridge = None;
    if let Some(t) = material.texture.filter(|t| t.amplitude > 0.0) {
        let (mut normal, mut total, mut centre) = (Vec3::ZERO, 0.0f32, Vec3::ZERO);
        for c in contacts.iter().filter(valid) {
            if let Some((n, _, magnitude)) = push(c) {
                normal += n * magnitude;
                total += magnitude;
                centre += c.point * magnitude;
            }
        }
        let along = normal.length();
        if total > 0.0 && along > 0.0 {
            let (n, centre) = (normal / along, centre / total);
            let ridged = t.apply(normal, centre, (object.orientation, object.center_of_mass), t.stiffness);
            scale_push = ridged.dot(n).max(0.0) / along;
            ridge = Some((ridged - n * ridged.dot(n), centre));
        }
    }
    let mut force = Vec3::ZERO;
    let mut torque = Vec3::ZERO;
    for c in contacts.iter().filter(valid) {
        let Some((n, v_rel, magnitude)) = push(c) else { continue };
        let magnitude = magnitude * scale_push;
        let mut f = n * magnitude;
        if mu > 0.0 && magnitude > 0.0 {
            let slip = v_rel - v_rel.dot(n) * n;
            let speed = slip.length();
            if speed > 0.0 {
                let fade = (speed / FRICTION_REGULARIZATION_M_PER_S).min(1.0);
                f -= slip / speed * (mu * magnitude * fade);
            }
        }
        let t = (c.point - tool.center_of_mass).cross(f);
        if f.is_finite() && t.is_finite() {
            force += f;
            torque += t;
        }
    }
    if let Some((slope, at)) = ridge.filter(|(f, at)| f.is_finite() && at.is_finite()) {
        force += slope;
        torque += (at - tool.center_of_mass).cross(slope);
    }
    let scale = if total_volume.is_finite() && total_volume > listed {
        (total_volume / listed).min(MAX_ESTIMATE_SCALE)
    } else {
        1.0
    };
    let out = ForceTorque { force: force * scale, torque: torque * scale };
    if out.is_finite() { out } else { ForceTorque::ZERO }
}

fn sanitize(v: Vec3) -> Vec3 {
    if v.is_finite() { v } else { Vec3::ZERO }
}

#[cfg(test)]
mod tests {
    use haptic_common::Contact;
    use proptest::prelude::*;

    use super::*;

    fn set(contacts: &[Contact]) -> ContactSet {
        let mut s = ContactSet::new();
        for c in contacts {
            s.push(*c);
            s.total_volume += c.volume;
        }
        s
    }

    fn contact(point: Vec3, normal: Vec3, volume: f32) -> Contact {
        Contact { point, normal, volume, depth: 0.0 }
    }

    const STIFF: Material = Material::new(3e6, 2.0);

    #[test]
    fn one_pair_at_rest_gives_volume_times_stiffness_and_its_lever_torque() {
        let s = set(&[contact(Vec3::new(0.01, 0.0, 0.0), Vec3::Z, 1e-6)]);
        let ft = volumetric_penalty(&s, &BodyMotion::default(), &BodyMotion::default(), &STIFF);
        assert!((ft.force - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-5, "{:?}", ft.force);
        // (0.01, 0, 0) x (0, 0, 3) = (0, -0.03, 0)
        assert!((ft.torque - Vec3::new(0.0, -0.03, 0.0)).length() < 1e-7, "{:?}", ft.torque);
    }

    #[test]
    fn symmetric_pairs_add_their_forces_and_cancel_their_torques() {
        let s = set(&[
            contact(Vec3::new(0.01, 0.0, 0.0), Vec3::Z, 1e-6),
            contact(Vec3::new(-0.01, 0.0, 0.0), Vec3::Z, 1e-6),
        ]);
        let ft = volumetric_penalty(&s, &BodyMotion::default(), &BodyMotion::default(), &STIFF);
        assert!((ft.force.z - 6.0).abs() < 1e-5);
        assert!(ft.torque.length() < 1e-7);
    }

    #[test]
    fn torque_is_taken_about_the_tools_centre_of_mass() {
        let s = set(&[contact(Vec3::new(0.01, 0.0, 0.0), Vec3::Z, 1e-6)]);
        let tool = BodyMotion::at_rest(Vec3::new(0.01, 0.0, 0.0));
        let ft = volumetric_penalty(&s, &tool, &BodyMotion::default(), &STIFF);
        assert!(ft.torque.length() < 1e-9);
    }

    #[test]
    fn moving_deeper_adds_damping_of_eps_d_times_the_approach_speed() {
        let s = set(&[contact(Vec3::ZERO, Vec3::Z, 1e-6)]);
        let tool = BodyMotion { linear_velocity: Vec3::new(0.0, 0.0, -0.1), ..Default::default() };
        let ft = volumetric_penalty(&s, &tool, &BodyMotion::default(), &STIFF);
        // vol * eps_c + eps_d * 0.1 * vol / vol_total = 3 + 0.2
        assert!((ft.force.z - 3.2).abs() < 1e-5, "{:?}", ft.force);
    }

    #[test]
    fn a_fast_separation_never_pulls_the_tool_back() {
        let s = set(&[contact(Vec3::ZERO, Vec3::Z, 1e-6)]);
        let tool = BodyMotion { linear_velocity: Vec3::new(0.0, 0.0, 10.0), ..Default::default() };
        let ft = volumetric_penalty(&s, &tool, &BodyMotion::default(), &STIFF);
        assert_eq!(ft.force, Vec3::ZERO);
    }

    #[test]
    fn the_object_moving_into_the_tool_counts_like_the_tool_moving_in() {
        let s = set(&[contact(Vec3::ZERO, Vec3::Z, 1e-6)]);
        let object = BodyMotion { linear_velocity: Vec3::new(0.0, 0.0, 0.1), ..Default::default() };
        let ft = volumetric_penalty(&s, &BodyMotion::default(), &object, &STIFF);
        assert!((ft.force.z - 3.2).abs() < 1e-5);
    }

    #[test]
    fn friction_opposes_sliding_with_mu_times_the_normal_force() {
        let s = set(&[contact(Vec3::ZERO, Vec3::Z, 1e-6)]);
        let tool = BodyMotion { linear_velocity: Vec3::new(0.05, 0.0, 0.0), ..Default::default() };
        let m = Material { friction: 0.5, ..STIFF };
        let ft = volumetric_penalty(&s, &tool, &BodyMotion::default(), &m);
        assert!((ft.force - Vec3::new(-1.5, 0.0, 3.0)).length() < 1e-5, "{:?}", ft.force);
    }

    #[test]
    fn a_ribbed_patch_pushes_less_over_a_groove_and_sideways_on_a_flank() {
        // 3 N of smooth push read at 3,000 N/m is 1 mm deep; grooves 0.4 mm deep every 3 mm along y.
        let ribbed = Material { texture: Some(crate::Texture::ribs(0.003, 0.0004, 3000.0)), ..STIFF };
        let at = |y: f32| {
            let s = set(&[contact(Vec3::new(0.0, y, 0.0), Vec3::Z, 1e-6)]);
            volumetric_penalty(&s, &BodyMotion::default(), &BodyMotion::default(), &ribbed).force
        };
        assert!((at(0.0) - Vec3::Z * 3.0).length() < 1e-4, "on a ridge: {}", at(0.0));
        assert!((at(0.0015) - Vec3::Z * 1.8).length() < 1e-4, "in a groove: {}", at(0.0015));
        let flank = at(0.00075);
        let slope = std::f32::consts::PI * 0.0004 / 0.003;
        assert!((flank.z - 2.4).abs() < 1e-3 && (flank.y - 2.4 * slope).abs() < 1e-3, "on a flank: {flank}");
    }

    #[test]
    fn volume_estimated_by_a_budgeted_query_scales_the_force_up() {
        let mut s = set(&[contact(Vec3::ZERO, Vec3::Z, 1e-6)]);
        s.total_volume = 2e-6;
        s.estimated_volume = 1e-6;
        let ft = volumetric_penalty(&s, &BodyMotion::default(), &BodyMotion::default(), &STIFF);
        assert!((ft.force.z - 6.0).abs() < 1e-5);
    }

    #[test]
    fn nan_contacts_are_skipped() {
        let s = set(&[
            contact(Vec3::ZERO, Vec3::Z, 1e-6),
            contact(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z, 1e-6),
            contact(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0), 1e-6),
            contact(Vec3::ZERO, Vec3::Z, f32::NAN),
        ]);
        let ft = volumetric_penalty(&s, &BodyMotion::default(), &BodyMotion::default(), &STIFF);
        assert!((ft.force.z - 3.0).abs() < 1e-5);
    }

    fn any_f32() -> impl Strategy<Value = f32> {
        prop_oneof![
            -1.0f32..1.0,
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(0.0),
            Just(f32::MAX),
            Just(f32::MIN_POSITIVE),
        ]
    }

    fn any_vec() -> impl Strategy<Value = Vec3> {
        (any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn any_contact_set_gives_a_finite_force(
            raw in prop::collection::vec((any_vec(), any_vec(), any_f32()), 0..8),
            v in any_vec(),
            total in any_f32(),
        ) {
            let mut s = ContactSet::new();
            for (p, n, vol) in raw {
                s.push(Contact { point: p, normal: n, volume: vol, depth: 0.0 });
            }
            s.total_volume = total;
            let tool = BodyMotion { linear_velocity: v, ..Default::default() };
            let ft = volumetric_penalty(&s, &tool, &BodyMotion::default(), &Material::default());
            prop_assert!(ft.is_finite());
        }
    }
}
