//! Rigid poses: a rotation followed by a translation, in metres.

use glam::{Quat, Vec3};

/// A rigid transform: `p_world = rotation * p_local + translation`. Units: metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Translation in metres.
    pub translation: Vec3,
    /// Unit rotation.
    pub rotation: Quat,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// The identity transform.
    pub const IDENTITY: Self = Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY };

    /// A pure translation.
    pub const fn from_translation(translation: Vec3) -> Self {
        Self { translation, rotation: Quat::IDENTITY }
    }

    /// A rotation followed by a translation.
    pub const fn new(translation: Vec3, rotation: Quat) -> Self {
        Self { translation, rotation }
    }

    /// Maps a point from local to world coordinates.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    /// Maps a direction (no translation).
    #[inline]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Self {
        let inv = self.rotation.inverse();
        Self { translation: -(inv * self.translation), rotation: inv }
    }

    /// `self * other`: first `other`, then `self`.
    #[inline]
    pub fn mul_pose(&self, other: &Pose) -> Self {
        Self {
            translation: self.transform_point(other.translation),
            rotation: (self.rotation * other.rotation).normalize(),
        }
    }

    /// The pose of object 2 relative to object 1 (`pos12` in parry's naming): `self.inverse() * other`.
    #[inline]
    pub fn relative_to(&self, other: &Pose) -> Self {
        self.inverse().mul_pose(other)
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_undoes_the_transform() {
        let p = Pose::new(Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_y(0.7));
        let x = Vec3::new(-0.5, 0.25, 4.0);
        let back = p.inverse().transform_point(p.transform_point(x));
        assert!((back - x).length() < 1e-5);
    }

    #[test]
    fn relative_pose_maps_object_two_into_object_one() {
        let a = Pose::new(Vec3::X, Quat::from_rotation_z(0.3));
        let b = Pose::new(Vec3::Y * 2.0, Quat::from_rotation_x(-1.1));
        let pos12 = a.relative_to(&b);
        let x = Vec3::new(0.1, 0.2, 0.3);
        let via_world = a.inverse().transform_point(b.transform_point(x));
        assert!((pos12.transform_point(x) - via_world).length() < 1e-5);
    }
}
