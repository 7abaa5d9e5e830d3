//! Enclosing spheres of sets of spheres (the "wrapped" bounds of tree nodes).

use crate::shape::Sphere;
use glam::Vec3;

/// A small sphere enclosing every sphere of `spheres` (not necessarily the minimal one).
///
/// Tries the volume-weighted centroid and the box centre, then keeps the tighter result. Returns a zero
/// sphere at the origin for an empty slice.
pub fn enclosing_sphere(spheres: &[Sphere]) -> Sphere {
    if spheres.is_empty() {
        return Sphere::default();
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
    for s in spheres {
        lo = lo.min(s.center - s.radius);
        hi = hi.max(s.center + s.radius);
        let w = s.radius * s.radius * s.radius;
        sum += s.center * w;
        weight += w;
    }
    let candidates = [(lo + hi) * 0.5, if weight > 0.0 { sum / weight } else { (lo + hi) * 0.5 }];
    let mut best = Sphere::new(candidates[0], f32::INFINITY);
    for c in candidates {
        let mut r = spheres.iter().fold(0.0f32, |r, s| r.max(c.distance(s.center) + s.radius));
        // A few Ritter-style steps towards the farthest sphere shrink the bound further.
        let mut c = c;
        for _ in 0..8 {
            let far = spheres
                .iter()
                .max_by(|a, b| (c.distance(a.center) + a.radius).total_cmp(&(c.distance(b.center) + b.radius)));
            let Some(far) = far else { break };
            let dir = far.center - c;
            let len = dir.length();
            if len <= 1e-12 {
                break;
            }
            let trial = c + dir / len * (r * 0.05);
            let tr = spheres.iter().fold(0.0f32, |r, s| r.max(trial.distance(s.center) + s.radius));
            if tr < r {
                c = trial;
                r = tr;
            } else {
                break;
            }
        }
        if r < best.radius {
            best = Sphere::new(c, r);
        }
    }
    // Guard against rounding: the bound must contain every sphere.
    best.radius *= 1.0 + 1e-6;
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_enclosing_sphere_contains_every_sphere() {
        let s = [Sphere::new(Vec3::ZERO, 1.0), Sphere::new(Vec3::X * 3.0, 0.5), Sphere::new(Vec3::Y * -2.0, 0.2)];
        let b = enclosing_sphere(&s);
        for x in &s {
            assert!(b.center.distance(x.center) + x.radius <= b.radius * 1.0001);
        }
        assert!(b.radius < 3.5);
    }
}
