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
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Diameter of the scene's gemstone tool, metres (1 cm).
pub const TOOL_DIAMETER: f32 = 0.01;

/// Factor from the bunny OBJ's units to metres: the shipped model is about 10 units tall, the scene's
/// bunny about 10 cm.
pub const BUNNY_SCALE: f32 = 0.01;

/// Sphere counts for a scene's two trees, as the benchmark tools take them: `N` for both, or `A:B`
/// (the first object, e.g. the tool, gets `a`; the second, e.g. the bunny, `b`). Shown the same way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SphereCounts {
    /// Spheres of the first object's tree.
    pub a: usize,
    /// Spheres of the second object's tree.
    pub b: usize,
}

impl FromStr for SphereCounts {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let count = |t: &str| t.trim().parse::<usize>().map_err(|e| format!("sphere count {:?}: {e}", t.trim()));
        match s.split_once(':') {
            Some((a, b)) => Ok(Self { a: count(a)?, b: count(b)? }),
            None => count(s).map(|n| Self { a: n, b: n }),
        }
    }
}

impl fmt::Display for SphereCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.a == self.b { write!(f, "{}", self.a) } else { write!(f, "{}:{}", self.a, self.b) }
    }
}

/// The bunny shipped in this package (`data/bunny.obj`, the Stanford bunny, public domain; in the
/// repository a link to the game's `assets/meshes/bunny.obj`), or `$COLLETTE_BUNNY` when set.
pub fn default_bunny_path() -> PathBuf {
    if let Some(p) = std::env::var_os("COLLETTE_BUNNY") {
        return PathBuf::from(p);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/bunny.obj")
}

/// Loads the bunny from an OBJ file, scaled by [`BUNNY_SCALE`] to metres and centred on its box centre.
pub fn load_bunny(path: impl AsRef<Path>) -> Result<TriMesh, MeshError> {
    let raw = TriMesh::from_obj(path)?;
    let center = raw.aabb().center();
    raw.map_vertices(|v| (v - center) * BUNNY_SCALE)
}

#[cfg(test)]
mod tests {
    use super::SphereCounts;

    #[test]
    fn sphere_counts_read_one_count_for_both_trees_or_one_each_and_show_back_the_same_way() {
        assert_eq!("10000".parse(), Ok(SphereCounts { a: 10_000, b: 10_000 }));
        assert_eq!(" 4000 : 20000 ".parse(), Ok(SphereCounts { a: 4_000, b: 20_000 }));
        assert_eq!(SphereCounts { a: 10_000, b: 10_000 }.to_string(), "10000");
        assert_eq!(SphereCounts { a: 4_000, b: 20_000 }.to_string(), "4000:20000");
        let bad = "10x".parse::<SphereCounts>().unwrap_err();
        assert!(bad.starts_with("sphere count \"10x\""), "{bad}");
        let bad = "1000:b".parse::<SphereCounts>().unwrap_err();
        assert!(bad.starts_with("sphere count \"b\""), "{bad}");
        assert!(":".parse::<SphereCounts>().is_err());
    }
}
