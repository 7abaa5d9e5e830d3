//! The haptic geometry of each kind: a profile swept around the vertical axis, with the copy's
//! features (crown points, amphora ridges, idol notches) carved into it at full, feelable size.

use std::f32::consts::TAU;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::kind::{ArtifactKind, CopyTraits};
use super::lathe::{close_rings, meridians, on_meridian};
use super::mesh::HapticMesh;

/// Height of a crown point above the rim between points, metres.
pub const CROWN_POINT_HEIGHT_M: f32 = 0.020;
/// How far an amphora ridge stands out of the belly, metres.
pub const AMPHORA_RIDGE_HEIGHT_M: f32 = 0.010;
/// Depth of an idol notch, metres.
pub const IDOL_NOTCH_DEPTH_M: f32 = 0.010;
/// Width of an idol notch at the surface, metres (wide enough for a 1 cm tool tip to sink in).
pub const IDOL_NOTCH_WIDTH_M: f32 = 0.016;

// Features a 1 cm tool tip can feel: at least 8 mm even when shrunk by 10 %, notches wider than the tip.
const _: () = assert!(
    0.9 * CROWN_POINT_HEIGHT_M >= 0.008
        && 0.9 * AMPHORA_RIDGE_HEIGHT_M >= 0.008 - 1e-6
        && 0.9 * IDOL_NOTCH_DEPTH_M >= 0.008 - 1e-6
        && IDOL_NOTCH_WIDTH_M >= 0.012
);

/// Builds the closed haptic mesh of one copy, metres, +y up, centred near the origin.
///
/// `seed` only turns the features around the axis and varies each feature's size by ±10 %; the
/// count and the outline come from `traits`.
pub fn build_mesh(traits: &CopyTraits, seed: u64) -> HapticMesh {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_A27F_AC75_0001);
    let n = traits.feature_count as usize;
    let phase = if n > 0 { rng.random_range(0.0..TAU / n as f32) } else { 0.0 };
    let scale: Vec<f32> = (0..n.max(1)).map(|_| rng.random_range(0.9..1.1)).collect();
    let features = Features { count: n, phase, scale };
    match traits.kind {
        ArtifactKind::Crown => crown(&features),
        ArtifactKind::Amphora => amphora(&features),
        ArtifactKind::Idol => idol(&features),
    }
}

/// `count` features evenly spaced around the axis.
struct Features {
    count: usize,
    /// Angle of the first feature's centre, radians.
    phase: f32,
    /// Size factor of each feature.
    scale: Vec<f32>,
}

impl Features {
    /// Meridians with `per_feature` of them per feature (one through each feature's centre), or
    /// `fallback` evenly spaced when there are no features.
    fn meridians(&self, per_feature: usize, fallback: usize) -> Vec<f32> {
        if self.count == 0 { meridians(fallback, 0.0) } else { meridians(self.count * per_feature, self.phase) }
    }

    /// Meridians crowded inside each feature: `across` of them over the central fraction
    /// `2 * half` of each spacing (edges included), and about one per `step` radians between.
    fn meridians_crowded(&self, half: f32, across: usize, step: f32, fallback: usize) -> Vec<f32> {
        if self.count == 0 {
            return meridians(fallback, 0.0);
        }
        let spacing = TAU / self.count as f32;
        let between = ((1.0 - 2.0 * half) * spacing / step).ceil().max(1.0) as usize;
        let mut phis = Vec::with_capacity(self.count * (across + between));
        for k in 0..self.count {
            let centre = self.phase + k as f32 * spacing;
            for i in 0..across {
                phis.push(centre + spacing * (-half + 2.0 * half * i as f32 / across as f32));
            }
            for i in 0..between {
                phis.push(centre + spacing * (half + (1.0 - 2.0 * half) * i as f32 / between as f32));
            }
        }
        phis
    }

    /// Nearest feature to angle `phi` and the signed distance to its centre as a fraction of the
    /// spacing (−0.5..0.5).
    fn nearest(&self, phi: f32) -> (usize, f32) {
        if self.count == 0 {
            return (0, 0.5);
        }
        let u = (phi - self.phase).rem_euclid(TAU) / TAU * self.count as f32;
        let k = u.round();
        ((k as usize) % self.count, u - k)
    }
}

/// Meridian count per feature giving at most `total` meridians overall, at least `min` per feature.
fn per_feature(count: usize, total: usize, min: usize) -> usize {
    total.checked_div(count).map_or(min, |per| per.max(min))
}

/// A ring of radius `r(phi)` at height `y(phi)` along each meridian.
fn ring(phis: &[f32], f: impl Fn(f32) -> (f32, f32)) -> Vec<Vec3> {
    phis.iter()
        .map(|&phi| {
            let (r, y) = f(phi);
            on_meridian(phi, r, y)
        })
        .collect()
}

/// Smoothstep from 0 at `a` to 1 at `b`.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A solid crown: a band 10 cm across with a bowl inside; its points rise from the rim as
/// triangular teeth, 1 cm thick.
fn crown(f: &Features) -> HapticMesh {
    const R: f32 = 0.050;
    const WALL: f32 = 0.010;
    const RI: f32 = R - WALL;
    const BOTTOM: f32 = -0.035;
    const RIM: f32 = 0.013;
    const FLOOR: f32 = -0.020;
    // Tips sit on a meridian each; the valleys between them too, so the outline is exact.
    let per = 2 * (per_feature(f.count, 84, 10) / 2);
    let phis = f.meridians(per, 84);
    let top = |phi: f32| {
        let (k, d) = f.nearest(phi);
        if f.count == 0 { RIM } else { RIM + CROWN_POINT_HEIGHT_M * f.scale[k] * (1.0 - 2.0 * d.abs()) }
    };
    let mut rings = vec![
        ring(&phis, |_| (0.35 * R, BOTTOM)),
        ring(&phis, |_| (0.7 * R, BOTTOM)),
        ring(&phis, |_| (R - 0.003, BOTTOM)),
        ring(&phis, |_| (R, BOTTOM + 0.003)),
    ];
    for s in [0.35, 0.7, 0.85, 1.0] {
        rings.push(ring(&phis, |phi| (R, BOTTOM + 0.003 + s * (top(phi) - BOTTOM - 0.003))));
    }
    rings.push(ring(&phis, |phi| (RI, top(phi))));
    for s in [0.15, 0.3, 0.65] {
        rings.push(ring(&phis, |phi| (RI, top(phi) + s * (FLOOR + 0.003 - top(phi)))));
    }
    rings.push(ring(&phis, |_| (RI, FLOOR + 0.003)));
    rings.push(ring(&phis, |_| (RI - 0.003, FLOOR)));
    rings.push(ring(&phis, |_| (0.45 * RI, FLOOR)));
    close_rings(Vec3::new(0.0, BOTTOM, 0.0), &rings, Vec3::new(0.0, FLOOR, 0.0))
}

/// A solid amphora 12 cm tall with a shallow mouth; its ridges run up the belly and fade out
/// towards the foot and the shoulder.
fn amphora(f: &Features) -> HapticMesh {
    // (radius, height) of the plain outline, bottom to top, metres.
    const OUTLINE: [(f32, f32); 18] = [
        (0.016, -0.060),
        (0.025, -0.060),
        (0.027, -0.057),
        (0.023, -0.050),
        (0.027, -0.044),
        (0.033, -0.036),
        (0.037, -0.026),
        (0.039, -0.016),
        (0.039, -0.008),
        (0.037, 0.002),
        (0.033, 0.013),
        (0.026, 0.024),
        (0.016, 0.034),
        (0.013, 0.044),
        (0.017, 0.054),
        (0.018, 0.060),
        (0.011, 0.060),
        (0.008, 0.053),
    ];
    let per = per_feature(f.count, 80, 8);
    let phis = f.meridians(per, 80);
    let ridge = |phi: f32| {
        let (k, d) = f.nearest(phi);
        // A rounded ridge covering the middle half of each spacing.
        if f.count == 0 || d.abs() >= 0.25 { 0.0 } else { f.scale[k] * (std::f32::consts::PI * d / 0.5).cos() }
    };
    let envelope = |y: f32| smoothstep(-0.048, -0.034, y) * (1.0 - smoothstep(0.004, 0.020, y));
    let rings: Vec<Vec<Vec3>> = OUTLINE
        .iter()
        .map(|&(r, y)| ring(&phis, |phi| (r + AMPHORA_RIDGE_HEIGHT_M * envelope(y) * ridge(phi), y)))
        .collect();
    close_rings(Vec3::new(0.0, -0.060, 0.0), &rings, Vec3::new(0.0, 0.053, 0.0))
}

/// A squat solid idol 11 cm tall on a plinth, with a head; its notches are V grooves running up the
/// body, fading out at the plinth and the shoulders.
fn idol(f: &Features) -> HapticMesh {
    const OUTLINE: [(f32, f32); 15] = [
        (0.020, -0.055),
        (0.040, -0.055),
        (0.043, -0.051),
        (0.043, -0.045),
        (0.036, -0.041),
        (0.036, -0.030),
        (0.035, -0.017),
        (0.034, -0.004),
        (0.032, 0.010),
        (0.027, 0.020),
        (0.016, 0.027),
        (0.022, 0.034),
        (0.024, 0.042),
        (0.020, 0.050),
        (0.010, 0.055),
    ];
    const BODY_R: f32 = 0.035;
    let half_width = 0.5 * IDOL_NOTCH_WIDTH_M / BODY_R / TAU * f.count.max(1) as f32;
    // Four meridians across each half notch, its bottom and edges included; sparse in between.
    let phis = f.meridians_crowded(half_width, 8, 0.08, 96);
    let notch = |phi: f32| {
        let (k, d) = f.nearest(phi);
        if f.count == 0 { 0.0 } else { f.scale[k] * (1.0 - d.abs() / half_width).max(0.0) }
    };
    let envelope = |y: f32| smoothstep(-0.042, -0.032, y) * (1.0 - smoothstep(0.0, 0.012, y));
    let rings: Vec<Vec<Vec3>> = OUTLINE
        .iter()
        .map(|&(r, y)| ring(&phis, |phi| (r - IDOL_NOTCH_DEPTH_M * envelope(y) * notch(phi), y)))
        .collect();
    close_rings(Vec3::new(0.0, -0.055, 0.0), &rings, Vec3::new(0.0, 0.055, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifact::kind::MaterialClass;

    fn traits(kind: ArtifactKind, feature_count: u32) -> CopyTraits {
        CopyTraits { kind, feature_count, material: MaterialClass::HardSmooth }
    }

    #[test]
    fn every_kind_and_count_gives_a_valid_closed_outward_mesh() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range().chain([0, 1, 12]) {
                for seed in 0..4 {
                    let mesh = build_mesh(&traits(kind, n), seed);
                    if let Err(e) = mesh.validate() {
                        panic!("{kind} with {n} features, seed {seed}: {e}");
                    }
                    assert!(mesh.signed_volume() > 5e-5, "{kind} {n}: volume {}", mesh.signed_volume());
                }
            }
        }
    }

    #[test]
    fn meshes_have_a_few_hundred_to_about_three_thousand_triangles() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range() {
                let t = build_mesh(&traits(kind, n), 1).triangle_count();
                assert!((300..=3000).contains(&t), "{kind} {n}: {t} triangles");
            }
        }
    }

    #[test]
    fn meshes_are_hand_sized_and_centred_near_the_origin() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range() {
                let (lo, hi) = build_mesh(&traits(kind, n), 3).bounds();
                let size = hi - lo;
                let centre = (hi + lo) * 0.5;
                assert!(size.max_element() <= 0.125 && size.max_element() >= 0.08, "{kind} {n}: {size}");
                assert!(centre.length() < 0.02, "{kind} {n}: centre {centre}");
            }
        }
    }

    #[test]
    fn the_shared_look_has_the_size_of_every_copy() {
        for kind in ArtifactKind::ALL {
            let look = crate::artifact::look(kind);
            for n in kind.feature_range() {
                let mesh = build_mesh(&traits(kind, n), u64::from(n));
                let (lo, hi) = mesh.bounds();
                let diameter = 2.0 * mesh.vertices.iter().map(|p| p[0].hypot(p[2])).fold(0.0, f32::max);
                assert!((diameter - look.size_m[0]).abs() < 0.005, "{kind} {n}: diameter {diameter}");
                assert!((hi.y - lo.y - look.size_m[1]).abs() < 0.005, "{kind} {n}: height {}", hi.y - lo.y);
            }
        }
    }

    #[test]
    fn the_same_traits_and_seed_give_the_same_mesh() {
        let t = traits(ArtifactKind::Crown, 7);
        assert_eq!(build_mesh(&t, 42), build_mesh(&t, 42));
        assert_ne!(build_mesh(&t, 42), build_mesh(&t, 43));
    }
}
