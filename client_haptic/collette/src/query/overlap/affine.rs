//! An affine map applied to four points at once (structure of arrays): the descent moves four of B's
//! centres into A's frame, the contact sink four contacts into the world.

use glam::{Affine3A, Vec4};

/// An affine map's entries, each in all four lanes: moves four points (structure of arrays) at once.
#[derive(Clone, Copy)]
pub(super) struct WideAffine {
    xx: Vec4,
    xy: Vec4,
    xz: Vec4,
    yx: Vec4,
    yy: Vec4,
    yz: Vec4,
    zx: Vec4,
    zy: Vec4,
    zz: Vec4,
    tx: Vec4,
    ty: Vec4,
    tz: Vec4,
}

impl WideAffine {
    pub(super) fn new(m: &Affine3A) -> Self {
        let (c0, c1, c2, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
        let s = Vec4::splat;
        Self {
            xx: s(c0.x),
            xy: s(c0.y),
            xz: s(c0.z),
            yx: s(c1.x),
            yy: s(c1.y),
            yz: s(c1.z),
            zx: s(c2.x),
            zy: s(c2.y),
            zz: s(c2.z),
            tx: s(t.x),
            ty: s(t.y),
            tz: s(t.z),
        }
    }

    /// Four points `(x, y, z)` mapped.
    #[inline(always)]
    pub(super) fn point(&self, x: Vec4, y: Vec4, z: Vec4) -> [Vec4; 3] {
        let [rx, ry, rz] = self.vector(x, y, z);
        [rx + self.tx, ry + self.ty, rz + self.tz]
    }

    /// Four vectors `(x, y, z)` mapped by the linear part alone.
    #[inline(always)]
    pub(super) fn vector(&self, x: Vec4, y: Vec4, z: Vec4) -> [Vec4; 3] {
        [
            self.xx * x + self.yx * y + self.zx * z,
            self.xy * x + self.yy * y + self.zy * z,
            self.xz * x + self.yz * y + self.zz * z,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    #[test]
    fn four_points_at_once_match_the_affine_map() {
        let m = Affine3A::from_rotation_translation(
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            Vec3::new(1.0, -2.0, 0.5),
        );
        let w = WideAffine::new(&m);
        let pts = [Vec3::new(0.1, 0.2, 0.3), Vec3::new(-4.0, 1.0, 2.0), Vec3::ZERO, Vec3::new(7.0, -7.0, 0.25)];
        let x = Vec4::from_array(pts.map(|p| p.x));
        let y = Vec4::from_array(pts.map(|p| p.y));
        let z = Vec4::from_array(pts.map(|p| p.z));
        let (p4, v4) = (w.point(x, y, z), w.vector(x, y, z));
        for (lane, p) in pts.iter().enumerate() {
            let got = Vec3::new(p4[0][lane], p4[1][lane], p4[2][lane]);
            assert!(got.distance(m.transform_point3(*p)) < 1e-5, "point {lane}");
            let got = Vec3::new(v4[0][lane], v4[1][lane], v4[2][lane]);
            assert!(got.distance(m.transform_vector3(*p)) < 1e-5, "vector {lane}");
        }
    }
}
