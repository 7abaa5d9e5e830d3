//! Closed meshes from a ring grid: a stack of rings swept around the vertical axis, capped by a
//! pole at each end. Whatever the ring shapes, the topology is a sphere, so the result is closed and
//! manifold by construction; it is valid as long as neighbouring rings do not touch.

use glam::Vec3;

use super::mesh::HapticMesh;

/// Angles, radians, of the `segments` meridians, starting at `phase` and going counter-clockwise
/// seen from above (from +x towards −z).
pub(crate) fn meridians(segments: usize, phase: f32) -> Vec<f32> {
    (0..segments).map(|j| phase + std::f32::consts::TAU * j as f32 / segments as f32).collect()
}

/// The point at radius `r` and height `y` on the meridian at angle `phi`, metres.
pub(crate) fn on_meridian(phi: f32, r: f32, y: f32) -> Vec3 {
    // −z so that increasing phi turns counter-clockwise seen from +y, in a right-handed frame.
    Vec3::new(r * phi.cos(), y, -r * phi.sin())
}

/// Builds the mesh of rings listed bottom to top (each with the same number of points, in
/// meridian order), closed by a pole below the first ring and one above the last.
pub(crate) fn close_rings(bottom_pole: Vec3, rings: &[Vec<Vec3>], top_pole: Vec3) -> HapticMesh {
    let segments = rings.first().map_or(0, Vec::len);
    debug_assert!(rings.iter().all(|r| r.len() == segments));
    let mut vertices = Vec::with_capacity(rings.len() * segments + 2);
    vertices.push(bottom_pole.to_array());
    for ring in rings {
        vertices.extend(ring.iter().map(|p| p.to_array()));
    }
    let top = vertices.len() as u32;
    vertices.push(top_pole.to_array());

    let at = |i: usize, j: usize| (1 + i * segments + j % segments) as u32;
    let mut triangles = Vec::with_capacity(2 * segments * rings.len());
    for j in 0..segments {
        triangles.push([0, at(0, j + 1), at(0, j)]);
    }
    for i in 0..rings.len().saturating_sub(1) {
        for j in 0..segments {
            let (a, b) = (at(i, j), at(i, j + 1));
            let (c, d) = (at(i + 1, j), at(i + 1, j + 1));
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    let last = rings.len().saturating_sub(1);
    for j in 0..segments {
        triangles.push([at(last, j), at(last, j + 1), top]);
    }
    HapticMesh { vertices, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_swept_cylinder_is_closed_and_outward() {
        let phis = meridians(24, 0.3);
        let rings: Vec<Vec<Vec3>> =
            [-0.05, 0.0, 0.05].iter().map(|&y| phis.iter().map(|&p| on_meridian(p, 0.04, y)).collect()).collect();
        let mesh = close_rings(Vec3::new(0.0, -0.05, 0.0), &rings, Vec3::new(0.0, 0.05, 0.0));
        assert_eq!(mesh.validate(), Ok(()));
        assert_eq!(mesh.triangle_count(), 2 * 24 * 3);
        // A 24-gon prism: 0.5 * n * r² * sin(2π/n) * h.
        let expected = 0.5 * 24.0 * 0.04f32.powi(2) * (std::f32::consts::TAU / 24.0).sin() * 0.1;
        assert!((mesh.signed_volume() - expected).abs() < expected * 1e-3);
    }
}
