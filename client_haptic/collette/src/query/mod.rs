//! Queries between trees (overlap volume, time-budgeted overlap, separation distance), between a tree
//! or a surface shell and a signed distance grid (overlap volume), and probes.
//!
//! You need this module to detect collisions. Every query takes the two objects' world poses (the
//! relative pose `pos12` maps object 2's frame into object 1's), a caller-owned [`QueryWorkspace`]
//! created once, and, where it reports contacts, a caller-owned [`ContactSet`]: in steady state no
//! query allocates.

pub mod distance;
pub mod field;
pub mod overlap;
pub mod probe;
pub mod shell;
pub mod surfaces;
mod workspace;

pub use distance::{Separation, separation};
pub use field::{overlap_field, overlap_field_budgeted, overlap_field_volume};
pub use overlap::{Budget, CoherenceStats, CoherentOverlap, OverlapResult, overlap, overlap_budgeted, overlap_volume};
pub use probe::{ProbeHit, probe, spheres_near};
pub use shell::{overlap_shell, overlap_shell_budgeted};
pub use surfaces::{overlap_surfaces, overlap_surfaces_budgeted};
pub use workspace::QueryWorkspace;

pub use haptic_common::{Contact, ContactSet, Pose};
