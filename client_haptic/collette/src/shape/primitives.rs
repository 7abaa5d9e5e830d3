//! Procedural closed meshes for tests, examples and benchmarks: boxes, UV spheres and tori.

use glam::Vec3;

/// The 8 corners and 12 triangles of an axis-aligned box (outward-facing); used by tests and examples.
pub fn box_buffers(half: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -half.x } else { half.x },
                if i & 2 == 0 { -half.y } else { half.y },
                if i & 4 == 0 { -half.z } else { half.z },
            )
        })
        .collect();
    let t = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6], // -z, +z
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7], // -y, +y
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5], // -x, +x
    ];
    (v, t)
}

/// A closed UV sphere of `radius` with `rings` latitude bands (>= 2) and `segments` longitudes (>= 3),
/// outward-facing. Its vertices lie on the sphere, so it is inscribed in the ideal ball.
pub fn uv_sphere_buffers(radius: f32, rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut v = vec![Vec3::new(0.0, 0.0, radius)];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            v.push(radius * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    v.push(Vec3::new(0.0, 0.0, -radius));
    let south = v.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * segments + (j % segments);
    let mut t = Vec::new();
    for j in 0..segments {
        t.push([0, at(1, j), at(1, j + 1)]);
        t.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    (v, t)
}

/// A closed torus around the z axis: tube centre `major` from the axis, tube radius `minor` (< `major`),
/// `rings` segments around the axis (>= 3) and `sides` around the tube (>= 3), outward-facing. Its
/// vertices lie on the ideal surface.
pub fn torus_buffers(major: f32, minor: f32, rings: u32, sides: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (rings, sides) = (rings.max(3), sides.max(3));
    let mut v = Vec::with_capacity((rings * sides) as usize);
    for i in 0..rings {
        let u = std::f32::consts::TAU * i as f32 / rings as f32;
        for j in 0..sides {
            let w = std::f32::consts::TAU * j as f32 / sides as f32;
            let r = major + minor * w.cos();
            v.push(Vec3::new(r * u.cos(), r * u.sin(), minor * w.sin()));
        }
    }
    let at = |i: u32, j: u32| (i % rings) * sides + (j % sides);
    let mut t = Vec::with_capacity((2 * rings * sides) as usize);
    for i in 0..rings {
        for j in 0..sides {
            t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    (v, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriMesh;

    #[test]
    fn a_fine_uv_sphere_is_closed_and_close_to_the_ball_volume() {
        let (v, t) = uv_sphere_buffers(1.0, 48, 96);
        let m = TriMesh::new(v, t).expect("closed");
        let ball = 4.0 / 3.0 * std::f32::consts::PI;
        assert!(m.volume() < ball && m.volume() > 0.98 * ball, "{}", m.volume());
    }

    #[test]
    fn a_fine_torus_is_closed_outward_and_close_to_its_volume() {
        let (v, t) = torus_buffers(3.0, 1.0, 96, 48);
        let m = TriMesh::new(v, t.clone()).expect("closed");
        assert_eq!(m.triangles(), &t[..], "already outward: nothing flipped");
        let ideal = 2.0 * std::f32::consts::PI.powi(2) * 3.0;
        assert!(m.volume() < ideal && m.volume() > 0.99 * ideal, "{} of {ideal}", m.volume());
    }
}
