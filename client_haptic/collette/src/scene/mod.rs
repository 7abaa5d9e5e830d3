//! The paper's benchmark scene (Fig. 8): a gemstone tool exploring the Stanford bunny.
//!
//! You need this module to reproduce the benchmark or to replay the same path in another crate: it
//! builds the procedural brilliant-cut tool, loads the bunny in metres, and generates the scripted
//! 35-second, 1 kHz tool trajectory (free space, grazing contact, deep interpenetration), which can be
//! written to and read from a CSV file. All of it is deterministic. This API is stable.

mod csv;
mod gem;
mod trajectory;

pub use csv::{read_trajectory_csv, write_trajectory_csv};
pub use gem::brilliant_cut;
pub use trajectory::{Phase, TRAJECTORY_RATE_HZ, TRAJECTORY_SECONDS, TrajectorySample, trajectory};

use crate::error::MeshError;
use crate::shape::TriMesh;
use std::path::{Path, PathBuf};

/// Diameter of the scene's gemstone tool, metres (1 cm).
pub const TOOL_DIAMETER: f32 = 0.01;

/// Factor from the bunny OBJ's units to metres: the shipped model is about 10 units tall, the scene's
/// bunny about 10 cm.
pub const BUNNY_SCALE: f32 = 0.01;

/// The bunny shipped with the project (`assets/meshes/bunny.obj`, the Stanford bunny, public domain), or
/// `$COLLETTE_BUNNY` when set.
pub fn default_bunny_path() -> PathBuf {
    if let Some(p) = std::env::var_os("COLLETTE_BUNNY") {
        return PathBuf::from(p);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/bunny.obj")
}

/// Loads the bunny from an OBJ file, scaled by [`BUNNY_SCALE`] to metres and centred on its box centre.
pub fn load_bunny(path: impl AsRef<Path>) -> Result<TriMesh, MeshError> {
    let raw = TriMesh::from_obj(path)?;
    let center = raw.aabb().center();
    raw.map_vertices(|v| (v - center) * BUNNY_SCALE)
}
