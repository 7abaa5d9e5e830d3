//! collette: Inner Sphere Trees (ISTs) for volumetric collision detection in haptics.
//!
//! An IST fills an object with non-overlapping spheres (greedy packing on a voxel distance field) and
//! wraps them in a hierarchy of bounding spheres. Two ISTs report the overlap volume of the objects
//! (a lower bound of the true intersection), every overlapping sphere pair with its exact lens volume,
//! normal and contact point: the input of volumetric penalty forces.
#![warn(missing_docs)]

pub mod bounding_volume;
pub mod error;
pub mod packing;
pub mod partitioning;
pub mod query;
pub mod scene;
pub mod shape;

pub use error::{BuildError, IstFileError, MeshError, TrajectoryError};
pub use packing::{BuildOptions, BuildProgress, BuildReport, build};
pub use partitioning::{InnerSphereTree, Node};
pub use shape::{Sphere, TriMesh};
