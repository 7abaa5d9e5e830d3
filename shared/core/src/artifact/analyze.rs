//! Telling copies apart from what they are, not from what they are called: the Phantom bot (and
//! any tool that must judge a copy) measures the feature count from the received mesh alone.
//!
//! The mesh is probed like a tool would: rays around the vertical axis read a circular profile
//! (rim height for a crown, belly radius for an amphora or an idol), and the features are counted
//! as the high (points, ridges) or low (notches) runs of that profile.

use std::f32::consts::TAU;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::briefing::Briefing;
use super::kind::{ArtifactKind, Material, MaterialClass};
use super::mesh::HapticMesh;

/// Number of probe rays around the axis (one every half degree).
pub const PROBE_RAYS: usize = 720;
/// Profiles varying less than this are featureless, metres.
pub const MIN_FEATURE_SIZE_M: f32 = 0.003;

/// What was measured on one copy's mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observed {
    /// The kind the mesh was analysed as.
    pub kind: ArtifactKind,
    /// Points, ridges or notches counted on the geometry.
    pub feature_count: u32,
    /// Peak-to-valley size of the probed profile, metres.
    pub feature_size_m: f32,
    /// Bounding box size (x, y, z), metres.
    pub size_m: [f32; 3],
}

/// Measures the feature count of a copy of `kind` from its mesh alone.
///
/// The mesh may be moved and turned about the vertical (+y) axis; it must stand upright.
pub fn analyze(kind: ArtifactKind, mesh: &HapticMesh) -> Observed {
    let (lo, hi) = mesh.bounds();
    // The features are spread evenly around the axis, so the solid's centroid lies on it.
    let axis = mesh.centroid();
    let profile = match kind {
        ArtifactKind::Crown => rim_heights(mesh, axis),
        ArtifactKind::Amphora => radii_at(mesh, axis, lo.y + 0.42 * (hi.y - lo.y)),
        ArtifactKind::Idol => radii_at(mesh, axis, lo.y + 0.35 * (hi.y - lo.y)),
    };
    let (min, max) = profile.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let feature_size_m = if profile.is_empty() { 0.0 } else { max - min };
    let feature_count = match kind {
        ArtifactKind::Crown | ArtifactKind::Amphora => count_high_runs(&profile),
        ArtifactKind::Idol => count_high_runs(&profile.iter().map(|v| -v).collect::<Vec<_>>()),
    };
    Observed { kind, feature_count, feature_size_m, size_m: (hi - lo).to_array() }
}

/// True when the observed copy fits the briefing.
///
/// Same kind, same feature count, and a material whose [`MaterialClass::nearest`] is the briefed one.
pub fn matches(briefing: &Briefing, observed: &Observed, material: &Material) -> bool {
    briefing.kind == observed.kind
        && briefing.feature_count == observed.feature_count
        && MaterialClass::nearest(material) == briefing.material
}

/// Judges a received copy: analyses `mesh` as the briefed kind and [`matches()`] it with `briefing`.
pub fn judge(briefing: &Briefing, mesh: &HapticMesh, material: &Material) -> bool {
    matches(briefing, &analyze(briefing.kind, mesh), material)
}

/// Height of the top surface just inside the outermost radius, around the vertical axis through
/// `axis`, metres.
fn rim_heights(mesh: &HapticMesh, axis: Vec3) -> Vec<f32> {
    let radius = |p: Vec3| (p.x - axis.x).hypot(p.z - axis.z);
    let r_max = mesh.vertices.iter().map(|p| radius(Vec3::from_array(*p))).fold(0.0f32, f32::max);
    let r = (r_max - 0.004).max(0.0);
    let (_, hi) = mesh.bounds();
    // Only triangles spanning the probe circle can be hit (1 mm margin covers the chords' sag).
    let near: Vec<[Vec3; 3]> = mesh
        .triangle_corners()
        .filter(|c| {
            let (a, b) = c.iter().fold((f32::INFINITY, 0.0f32), |(a, b), p| (a.min(radius(*p)), b.max(radius(*p))));
            a - 0.001 <= r && r <= b + 0.001
        })
        .collect();
    probe_angles()
        .map(|phi| {
            let origin = Vec3::new(axis.x + r * phi.cos(), hi.y + 0.01, axis.z - r * phi.sin());
            let t = near.iter().filter_map(|c| ray_hit(origin, Vec3::NEG_Y, c)).fold(f32::INFINITY, f32::min);
            if t.is_finite() { origin.y - t } else { hi.y - 1.0 }
        })
        .collect()
}

/// Outermost surface radius at height `y` around the vertical axis through `axis`, metres.
fn radii_at(mesh: &HapticMesh, axis: Vec3, y: f32) -> Vec<f32> {
    let near: Vec<[Vec3; 3]> = mesh
        .triangle_corners()
        .filter(|c| {
            let (a, b) = c.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
            a <= y && y <= b
        })
        .collect();
    probe_angles()
        .map(|phi| {
            let origin = Vec3::new(axis.x, y, axis.z);
            let dir = Vec3::new(phi.cos(), 0.0, -phi.sin());
            near.iter().filter_map(|c| ray_hit(origin, dir, c)).fold(0.0, f32::max)
        })
        .collect()
}

/// The probe angles, radians.
fn probe_angles() -> impl Iterator<Item = f32> {
    (0..PROBE_RAYS).map(|i| TAU * i as f32 / PROBE_RAYS as f32)
}

/// Distance along `dir` (unit) from `origin` to triangle `c`, if the ray hits it (either side).
fn ray_hit(origin: Vec3, dir: Vec3, c: &[Vec3; 3]) -> Option<f32> {
    // Möller–Trumbore.
    let e1 = c[1] - c[0];
    let e2 = c[2] - c[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = origin - c[0];
    let u = s.dot(p) / det;
    if !(-1e-6..=1.0 + 1e-6).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    if v < -1e-6 || u + v > 1.0 + 1e-6 {
        return None;
    }
    let t = e2.dot(q) / det;
    (t >= 0.0).then_some(t)
}

/// Number of separate stretches where a circular profile is high, with hysteresis so that
/// tessellation ripples (or a probe's noise) do not count: a run starts above 65 % of the
/// peak-to-valley range and ends below 35 %; a profile varying less than [`MIN_FEATURE_SIZE_M`] has none.
pub fn count_high_runs(profile: &[f32]) -> u32 {
    let Some(start) = profile.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i) else {
        return 0;
    };
    let min = profile[start];
    let max = profile.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if max - min < MIN_FEATURE_SIZE_M {
        return 0;
    }
    let (enter, leave) = (min + 0.65 * (max - min), min + 0.35 * (max - min));
    let mut high = false;
    let mut runs = 0;
    // Starting at the global minimum, the circle begins and ends low: no run is cut in two.
    for i in 0..profile.len() {
        let v = profile[(start + i) % profile.len()];
        if !high && v > enter {
            high = true;
            runs += 1;
        } else if high && v < leave {
            high = false;
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifact::{CopyTraits, briefing, build_mesh, generate_copies};

    #[test]
    fn analysis_recovers_the_feature_count_of_every_kind_count_and_seed() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range().chain([0, 1, 10]) {
                for seed in 0..6 {
                    let traits = CopyTraits { kind, feature_count: n, material: MaterialClass::HardRough };
                    let seed = seed * 1_000_003 + u64::from(n);
                    let observed = analyze(kind, &build_mesh(&traits, seed));
                    assert_eq!(observed.feature_count, n, "{kind} with {n} features, seed {seed}: {observed:?}");
                }
            }
        }
    }

    #[test]
    fn analysis_does_not_care_where_the_copy_stands_or_which_way_it_faces() {
        for kind in ArtifactKind::ALL {
            let n = *kind.feature_range().end();
            let traits = CopyTraits { kind, feature_count: n, material: MaterialClass::SoftSmooth };
            let mesh = build_mesh(&traits, 77);
            let (sin, cos) = 0.7f32.sin_cos();
            let moved = HapticMesh {
                vertices: mesh
                    .vertices
                    .iter()
                    .map(|p| [cos * p[0] + sin * p[2] + 0.4, p[1] + 0.9, -sin * p[0] + cos * p[2] - 1.3])
                    .collect(),
                triangles: mesh.triangles.clone(),
            };
            assert_eq!(moved.validate(), Ok(()));
            assert_eq!(analyze(kind, &moved).feature_count, n, "{kind}");
        }
    }

    #[test]
    fn features_measure_at_least_eight_millimetres() {
        for kind in ArtifactKind::ALL {
            for n in kind.feature_range() {
                let traits = CopyTraits { kind, feature_count: n, material: MaterialClass::HardRough };
                let observed = analyze(kind, &build_mesh(&traits, 5));
                assert!(observed.feature_size_m >= 0.008, "{kind} {n}: {observed:?}");
            }
        }
    }

    #[test]
    fn matches_picks_exactly_the_real_copy() {
        for kind in ArtifactKind::ALL {
            for seed in 0..25 {
                let (copies, real) = generate_copies(kind, seed, 3 + (seed as usize % 3));
                let b = briefing(&copies[real]);
                let picked: Vec<usize> = copies
                    .iter()
                    .enumerate()
                    .filter(|(i, c)| {
                        let mesh = build_mesh(c, seed.wrapping_mul(31).wrapping_add(*i as u64));
                        judge(&b, &mesh, &c.material.material())
                    })
                    .map(|(i, _)| i)
                    .collect();
                assert_eq!(picked, vec![real], "{kind} seed {seed}: {copies:?}");
            }
        }
    }

    #[test]
    fn a_briefing_for_another_kind_never_matches() {
        let t = CopyTraits { kind: ArtifactKind::Crown, feature_count: 6, material: MaterialClass::HardSmooth };
        let mut b = briefing(&t);
        b.kind = ArtifactKind::Idol;
        let observed = analyze(ArtifactKind::Crown, &build_mesh(&t, 1));
        assert!(!matches(&b, &observed, &t.material.material()));
    }

    #[test]
    fn an_empty_or_broken_mesh_has_no_features_and_does_not_panic() {
        assert_eq!(analyze(ArtifactKind::Amphora, &HapticMesh::default()).feature_count, 0);
        let broken = HapticMesh { vertices: vec![[0.0, f32::NAN, 0.0]], triangles: vec![[0, 5, 9]] };
        for kind in ArtifactKind::ALL {
            assert_eq!(analyze(kind, &broken).feature_count, 0);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        #[test]
        fn any_generated_copy_is_valid_and_analysed_exactly(kind_index in 0usize..3, seed: u64, build_seed: u64) {
            let kind = ArtifactKind::ALL[kind_index];
            let (copies, real) = generate_copies(kind, seed, 3);
            let b = briefing(&copies[real]);
            for (i, c) in copies.iter().enumerate() {
                let mesh = build_mesh(c, build_seed.wrapping_add(i as u64));
                proptest::prop_assert_eq!(mesh.validate(), Ok(()));
                let observed = analyze(kind, &mesh);
                proptest::prop_assert_eq!(observed.feature_count, c.feature_count);
                proptest::prop_assert_eq!(matches(&b, &observed, &c.material.material()), i == real);
            }
        }
    }
}
