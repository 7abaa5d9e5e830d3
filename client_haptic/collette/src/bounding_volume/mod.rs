//! Bounding volumes: axis-aligned boxes (grids, regions) and enclosing spheres of sphere sets (tree nodes).
//!
//! You need this module to restrict the collision thread to a region, or to read a tree's bounds.

mod aabb;
mod bounding_sphere;

pub use aabb::Aabb;
pub use bounding_sphere::enclosing_sphere;
