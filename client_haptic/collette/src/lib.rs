#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod bounding_volume;
#[cfg(feature = "cli")]
pub mod cli;
pub mod error;
pub mod io;
pub mod packing;
pub mod partitioning;
pub mod pipeline;
pub mod query;
#[cfg(feature = "cli")]
pub mod render;
pub mod scene;
pub mod shape;

pub use error::{BuildError, IstFileError, MeshError, SkinError, TrajectoryError};
pub use packing::{BuildOptions, BuildProgress, BuildReport, build};
pub use partitioning::{InnerSphereTree, Node};
pub use pipeline::{CollisionConfig, CollisionHandle, CollisionThread, ContactReader, ObjectId, PoseWriter, WatcherId};
pub use query::{
    Budget, CoherenceStats, CoherentOverlap, OverlapResult, ProbeHit, QueryWorkspace, Separation, overlap,
    overlap_budgeted, overlap_field, overlap_field_budgeted, overlap_field_volume, overlap_shell,
    overlap_shell_budgeted, overlap_surfaces, overlap_surfaces_budgeted, overlap_volume, probe, separation,
};
pub use shape::{SignedDistanceGrid, Sphere, SurfaceShell, TriMesh};

/// Types shared with the other haptic crates, re-exported for convenience.
pub use haptic_common::{Contact, ContactSet, MAX_CONTACTS, Pose};
