//! collette: Inner Sphere Trees (ISTs) for volumetric collision detection in haptics.
//!
//! An IST fills an object with non-overlapping spheres (greedy packing on a voxel distance field),
//! weighs each by the share of the mesh it stands for (itself and the nearest gaps) and wraps them in a
//! hierarchy of bounding spheres. Two ISTs report the overlap volume of the objects (the lens volumes of
//! their overlapping sphere pairs, each times both weights: an estimate of the true intersection), every
//! overlapping sphere pair with its volume, normal and contact point: the input of volumetric penalty
//! forces.
//!
//! - Build: [`TriMesh::from_obj`] / [`TriMesh::from_buffers`], then [`build`] with [`BuildOptions`].
//! - Store: [`InnerSphereTree::save`] / [`InnerSphereTree::load`] (the `.ist` format, see [`io`]).
//! - Query: [`overlap()`], [`overlap_budgeted`], [`overlap_volume`], [`probe()`], [`separation`], each with a
//!   caller-owned [`QueryWorkspace`] and (for contacts) a [`ContactSet`]; [`CoherentOverlap`] keeps a
//!   neighbour list between one pair's exact queries (temporal coherence); [`overlap_field`] measures a
//!   tree against a [`SignedDistanceGrid`] of the touched mesh (the surface, not its packing).
//! - Run: [`CollisionThread::spawn`] gives a [`CollisionHandle`]; poses in through [`PoseWriter`],
//!   contacts out through [`ContactReader`].
//! - Benchmark scene (gemstone tool, bunny, scripted trajectory): [`scene`].
#![warn(missing_docs)]

pub mod bounding_volume;
pub mod cli;
pub mod error;
pub mod io;
pub mod packing;
pub mod partitioning;
pub mod pipeline;
pub mod query;
pub mod render;
pub mod scene;
pub mod shape;

pub use error::{BuildError, IstFileError, MeshError, SkinError, TrajectoryError};
pub use packing::{BuildOptions, BuildProgress, BuildReport, build};
pub use partitioning::{InnerSphereTree, Node};
pub use pipeline::{CollisionConfig, CollisionHandle, CollisionThread, ContactReader, ObjectId, PoseWriter, WatcherId};
pub use query::{
    Budget, CoherenceStats, CoherentOverlap, OverlapResult, ProbeHit, QueryWorkspace, Separation, overlap,
    overlap_budgeted, overlap_field, overlap_field_budgeted, overlap_field_volume, overlap_volume, probe, separation,
};
pub use shape::{SignedDistanceGrid, Sphere, TriMesh};

/// Types shared with the other haptic crates, re-exported for convenience.
pub use haptic_common::{Contact, ContactSet, MAX_CONTACTS, Pose};
