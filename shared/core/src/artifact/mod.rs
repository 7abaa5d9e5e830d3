//! Procedural artifacts: the real copy and the fakes of each target, their haptic meshes and
//! materials, the spoken briefing, and feature extraction from a mesh.
//!
//! You need this module to set up a heist (server: [`generate_copies`], [`build_mesh`],
//! [`briefing`]), to show an artifact to the sighted player ([`look`], which carries no trait), to
//! render a copy haptically ([`HapticMesh`], [`Material`]), or to judge a copy from its geometry
//! like the Phantom bot does ([`analyze`], [`matches`]). Everything here is pure and deterministic
//! for a seed. Coordinates are metres, +y up; see `docs/artifacts.md`.

mod analyze;
mod briefing;
mod generate;
mod kind;
mod lathe;
mod mesh;
mod shapes;

pub use analyze::{MIN_FEATURE_SIZE_M, Observed, PROBE_RAYS, analyze, matches};
pub use briefing::{Briefing, briefing, number_in_words};
pub use generate::{MIN_COPIES, generate_copies};
pub use kind::{ArtifactKind, ArtifactLook, CopyTraits, Material, MaterialClass, look};
pub use mesh::{HapticMesh, MIN_TRIANGLE_AREA_M2, MeshError};
pub use shapes::{AMPHORA_RIDGE_HEIGHT_M, CROWN_POINT_HEIGHT_M, IDOL_NOTCH_DEPTH_M, IDOL_NOTCH_WIDTH_M, build_mesh};
