//! Spheres and the exact geometry of two overlapping spheres (the lens).

use glam::{Vec3, Vec4};
use std::f32::consts::PI;

/// A ball: centre and radius, in the units of its tree (metres for the scene helpers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (>= 0).
    pub radius: f32,
}

impl Sphere {
    /// A sphere from centre and radius.
    pub const fn new(center: Vec3, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Volume, `4/3 π r³`.
    #[inline]
    pub fn volume(&self) -> f32 {
        sphere_volume(self.radius)
    }

    /// True when the two balls overlap with a positive volume.
    #[inline]
    pub fn intersects(&self, other: &Sphere) -> bool {
        let r = self.radius + other.radius;
        self.center.distance_squared(other.center) < r * r
    }
}

/// Volume of a ball of radius `r`.
#[inline]
pub fn sphere_volume(r: f32) -> f32 {
    4.0 / 3.0 * PI * r * r * r
}

/// Exact volume of the intersection (lens) of two balls with radii `r1`, `r2` and centre distance `d`.
///
/// `π (r1 + r2 − d)² (d² + 2d(r1 + r2) − 3(r1 − r2)²) / (12 d)`; 0 when apart, the smaller ball when one
/// contains the other. It rises C¹-smoothly from first contact.
#[inline]
pub fn lens_volume(r1: f32, r2: f32, d: f32) -> f32 {
    let s = r1 + r2;
    if d >= s {
        return 0.0;
    }
    let diff = (r1 - r2).abs();
    if d <= diff {
        return sphere_volume(r1.min(r2));
    }
    let t = s - d;
    let v = PI * t * t * (d * d + 2.0 * d * s - 3.0 * diff * diff) / (12.0 * d);
    v.max(0.0)
}

/// Volume of a spherical cap of height `h` (0..=2r) cut from a ball of radius `r`.
#[inline(always)]
pub(crate) fn cap_volume(r: f32, h: f32) -> f32 {
    PI * h * h * (3.0 * r - h) / 3.0
}

/// A cap's volume times the distance from the ball's centre to the cap's centroid (its first moment
/// along the axis): `π h² (2r − h)² / 4` for a cap of height `h` cut from a ball of radius `r`.
#[inline(always)]
pub(crate) fn cap_moment(r: f32, h: f32) -> f32 {
    let a = h * (2.0 * r - h);
    PI * 0.25 * a * a
}

/// Geometry of the overlap of two balls.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lens {
    /// Overlap volume.
    pub volume: f32,
    /// Centroid of the overlap (the contact point).
    pub centroid: Vec3,
    /// Penetration depth `r1 + r2 − d`.
    pub depth: f32,
}

/// The lens of two balls, or `None` when they do not overlap. The centroid lies on the centre line; when
/// one ball contains the other it is the smaller ball's centre.
///
/// Two divisions and one square root: the caps' centroids enter through their first moments.
#[inline(always)]
pub fn lens(c1: Vec3, r1: f32, c2: Vec3, r2: f32) -> Option<Lens> {
    let delta = c2 - c1;
    let d2 = delta.length_squared();
    let s = r1 + r2;
    if d2 >= s * s {
        return None;
    }
    let d = d2.sqrt();
    let depth = s - d;
    if d <= (r1 - r2).abs() {
        let (c, r) = if r1 <= r2 { (c1, r1) } else { (c2, r2) };
        return Some(Lens { volume: sphere_volume(r), centroid: c, depth });
    }
    let inv_d = 1.0 / d;
    let u = delta * inv_d;
    // Distance from c1 to the radical plane; the lens is cap 1 (beyond the plane) plus cap 2.
    let x1 = (d2 + r1 * r1 - r2 * r2) * 0.5 * inv_d;
    let h1 = (r1 - x1).clamp(0.0, 2.0 * r1);
    let h2 = (r2 - (d - x1)).clamp(0.0, 2.0 * r2);
    let v1 = cap_volume(r1, h1);
    let v2 = cap_volume(r2, h2);
    let volume = v1 + v2;
    if volume <= 0.0 {
        return Some(Lens { volume: 0.0, centroid: c1 + u * x1, depth });
    }
    // Cap 1's centroid lies beyond c1 along u, cap 2's before c2.
    let moment = c1 * v1 + c2 * v2 + u * (cap_moment(r1, h1) - cap_moment(r2, h2));
    Some(Lens { volume, centroid: moment * (1.0 / volume), depth })
}

/// Four lenses at once ([`lens`] lane by lane, structure of arrays): centres `c1`, `c2` as x, y, z
/// lanes. Lanes whose balls do not overlap get volume 0.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lens4 {
    pub volume: Vec4,
    pub centroid: [Vec4; 3],
    pub depth: Vec4,
    /// One over the centres' distance (infinite where they coincide): the normal without another root.
    pub inv_d: Vec4,
}

/// [`lens`] for four pairs of balls at once.
#[inline(always)]
pub(crate) fn lens_x4(c1: [Vec4; 3], r1: Vec4, c2: [Vec4; 3], r2: Vec4) -> Lens4 {
    let delta = [c2[0] - c1[0], c2[1] - c1[1], c2[2] - c1[2]];
    let d2 = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
    let s = r1 + r2;
    let apart = d2.cmpge(s * s);
    let d = d2.sqrt();
    let depth = s - d;
    let inside = d.cmple((r1 - r2).abs());
    let inv_d = d.recip();
    let x1 = (d2 + r1 * r1 - r2 * r2) * Vec4::splat(0.5) * inv_d;
    let h1 = (r1 - x1).clamp(Vec4::ZERO, r1 * 2.0);
    let h2 = (r2 - (d - x1)).clamp(Vec4::ZERO, r2 * 2.0);
    let third = Vec4::splat(PI / 3.0);
    let v1 = third * h1 * h1 * (r1 * 3.0 - h1);
    let v2 = third * h2 * h2 * (r2 * 3.0 - h2);
    let (a1, a2) = (h1 * (r1 * 2.0 - h1), h2 * (r2 * 2.0 - h2));
    let moment = Vec4::splat(PI * 0.25) * (a1 * a1 - a2 * a2) * inv_d;
    let lens_volume = v1 + v2;
    let inv_v = lens_volume.recip();
    // The smaller ball when one contains the other.
    let first_smaller = r1.cmple(r2);
    let small_r = r1.min(r2);
    let small_volume = Vec4::splat(4.0 / 3.0 * PI) * small_r * small_r * small_r;
    let mut centroid = [Vec4::ZERO; 3];
    for k in 0..3 {
        let lens_c = (c1[k] * v1 + c2[k] * v2 + delta[k] * moment) * inv_v;
        let small_c = Vec4::select(first_smaller, c1[k], c2[k]);
        centroid[k] = Vec4::select(inside, small_c, lens_c);
    }
    let volume = Vec4::select(inside, small_volume, lens_volume.max(Vec4::ZERO));
    Lens4 { volume: Vec4::select(apart, Vec4::ZERO, volume), centroid, depth, inv_d }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint-rule integration of the lens on a fine grid (reference for the closed forms).
    fn integrate(r1: f32, r2: f32, d: f32, n: usize) -> (f64, f64) {
        let (r1, r2, d) = (r1 as f64, r2 as f64, d as f64);
        let x0 = -r1;
        let x1 = d + r2;
        let y = r1.min(r2);
        let (hx, hy) = ((x1 - x0) / n as f64, 2.0 * y / n as f64);
        let (mut vol, mut mx) = (0.0, 0.0);
        for i in 0..n {
            let x = x0 + (i as f64 + 0.5) * hx;
            for j in 0..n {
                let py = -y + (j as f64 + 0.5) * hy;
                for k in 0..n {
                    let pz = -y + (k as f64 + 0.5) * hy;
                    let q = py * py + pz * pz;
                    if x * x + q < r1 * r1 && (x - d) * (x - d) + q < r2 * r2 {
                        vol += 1.0;
                        mx += x;
                    }
                }
            }
        }
        let cell = hx * hy * hy;
        (vol * cell, if vol > 0.0 { mx / vol } else { 0.0 })
    }

    #[test]
    fn lens_volume_matches_numerical_integration() {
        for &(r1, r2, d) in &[(1.0, 1.0, 1.0), (1.0, 0.5, 1.2), (0.7, 1.3, 0.9), (1.0, 0.3, 0.8), (2.0, 1.0, 2.9)] {
            let exact = lens_volume(r1, r2, d);
            let (num, cx) = integrate(r1, r2, d, 160);
            let rel = (exact as f64 - num).abs() / num;
            assert!(rel < 0.01, "r1={r1} r2={r2} d={d}: exact {exact} numeric {num}");
            let l = lens(Vec3::ZERO, r1, Vec3::X * d, r2).expect("overlap");
            assert!((l.volume - exact).abs() <= 1e-4 * exact.max(1e-6), "closed forms agree");
            assert!((l.centroid.x as f64 - cx).abs() < 0.01 * (r1 + r2) as f64, "centroid {} vs {cx}", l.centroid.x);
        }
    }

    #[test]
    fn lens_volume_is_zero_apart_and_the_small_ball_when_contained() {
        assert_eq!(lens_volume(1.0, 1.0, 2.0), 0.0);
        assert_eq!(lens_volume(1.0, 1.0, 3.0), 0.0);
        assert!((lens_volume(2.0, 0.5, 0.5) - sphere_volume(0.5)).abs() < 1e-6);
        assert!(lens(Vec3::ZERO, 1.0, Vec3::X * 2.5, 1.0).is_none());
    }

    #[test]
    fn four_lenses_at_once_match_one_at_a_time() {
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..2_000 {
            let mut c1 = [Vec4::ZERO; 3];
            let mut c2 = [Vec4::ZERO; 3];
            let (mut r1, mut r2) = (Vec4::ZERO, Vec4::ZERO);
            for lane in 0..4 {
                for k in 0..3 {
                    c1[k][lane] = next() * 2.0 - 1.0;
                    c2[k][lane] = next() * 2.0 - 1.0;
                }
                r1[lane] = 0.05 + next();
                r2[lane] = 0.05 + next() * 0.5;
            }
            // One lane with the balls concentric.
            for k in 0..3 {
                c2[k][3] = c1[k][3];
            }
            let four = lens_x4(c1, r1, c2, r2);
            for lane in 0..4 {
                let p = |c: [Vec4; 3]| Vec3::new(c[0][lane], c[1][lane], c[2][lane]);
                let one = lens(p(c1), r1[lane], p(c2), r2[lane]);
                let (v, c) = one.map_or((0.0, Vec3::ZERO), |l| (l.volume, l.centroid));
                let scale = (r1[lane] + r2[lane]).powi(3);
                assert!((four.volume[lane] - v).abs() <= 1e-5 * scale, "lane {lane}: {} vs {v}", four.volume[lane]);
                if v > 1e-4 * scale {
                    assert!(p(four.centroid).distance(c) <= 1e-4, "lane {lane}: {} vs {c}", p(four.centroid));
                    let depth = one.map_or(0.0, |l| l.depth);
                    assert!((four.depth[lane] - depth).abs() <= 1e-5, "lane {lane} depth");
                }
            }
        }
    }

    #[test]
    fn lens_volume_is_continuous_at_containment() {
        let (r1, r2) = (1.0f32, 0.4f32);
        let at = lens_volume(r1, r2, 0.6 + 1e-4);
        assert!((at - sphere_volume(0.4)).abs() < 1e-3 * sphere_volume(0.4));
    }
}
