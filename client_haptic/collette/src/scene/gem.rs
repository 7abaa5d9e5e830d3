//! A procedural round brilliant cut (simplified: table, 16-sided crown and girdle, pavilion to a culet).

use crate::shape::TriMesh;
use glam::Vec3;
use std::f32::consts::TAU;

/// A closed brilliant-cut gemstone of girdle `diameter` (metres), centred on its girdle, table up (+z).
///
/// Tolkowsky proportions: table 53 % of the diameter, crown 16.2 %, girdle 2 %, pavilion 43.1 %; an
/// octagonal table, 16 girdle facets each side, crown and pavilion facets down to a point culet.
/// Panics only if `diameter` is not a positive finite number (the mesh is otherwise valid by construction).
pub fn brilliant_cut(diameter: f32) -> TriMesh {
    let r = diameter * 0.5;
    let (table_r, crown, girdle, pavilion) = (0.53 * r, 0.162 * diameter, 0.02 * diameter, 0.431 * diameter);
    let (zt, zg) = (girdle * 0.5 + crown, girdle * 0.5);
    let ring = |n: usize, radius: f32, z: f32| -> Vec<Vec3> {
        (0..n)
            .map(|k| {
                let a = TAU * k as f32 / n as f32;
                Vec3::new(radius * a.cos(), radius * a.sin(), z)
            })
            .collect()
    };
    let mut v = vec![Vec3::new(0.0, 0.0, zt)];
    let t0 = v.len() as u32;
    v.extend(ring(8, table_r, zt));
    let gt = v.len() as u32;
    v.extend(ring(16, r, zg));
    let gb = v.len() as u32;
    v.extend(ring(16, r, -zg));
    let culet = v.len() as u32;
    v.push(Vec3::new(0.0, 0.0, -zg - pavilion));
    let (t, g) = (|k: u32| t0 + k % 8, |base: u32, j: u32| base + j % 16);
    let mut tris = Vec::new();
    for k in 0..8 {
        tris.push([0, t(k), t(k + 1)]);
        // Crown: table edge k..k+1 over girdle vertices 2k..2k+2 (upper ring, lower ring, outward).
        tris.push([t(k), g(gt, 2 * k), g(gt, 2 * k + 1)]);
        tris.push([t(k), g(gt, 2 * k + 1), t(k + 1)]);
        tris.push([t(k + 1), g(gt, 2 * k + 1), g(gt, 2 * k + 2)]);
    }
    for j in 0..16 {
        tris.push([g(gt, j), g(gb, j), g(gb, j + 1)]);
        tris.push([g(gt, j), g(gb, j + 1), g(gt, j + 1)]);
        tris.push([g(gb, j), culet, g(gb, j + 1)]);
    }
    TriMesh::new(v, tris).unwrap_or_else(|e| panic!("brilliant_cut({diameter}): {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_brilliant_cut_is_a_closed_centimetre_gem() {
        let g = brilliant_cut(0.01);
        let e = g.aabb().extents();
        assert!((e.x - 0.01).abs() < 1e-4 && e.z > 0.005 && e.z < 0.007, "{e}");
        assert!(g.volume() > 0.0 && g.triangles().len() == 80);
    }
}
