//! Axis-aligned bounding boxes.

use glam::Vec3;

/// An axis-aligned box given by its corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (inverted, so that growing it by a point gives that point).
    pub const EMPTY: Self = Self { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// A box from two corners.
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding all points (EMPTY for none).
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| Self { min: b.min.min(p), max: b.max.max(p) })
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Size along each axis.
    pub fn extents(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// True when the box contains the point (boundary included).
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when the ball (centre, radius) touches the box.
    pub fn intersects_sphere(&self, center: Vec3, radius: f32) -> bool {
        let q = center.clamp(self.min, self.max);
        q.distance_squared(center) <= radius * radius
    }
}
