//! Procedural artifacts: the real copy and the fakes of each target, their haptic meshes and
//! materials, the spoken briefing, and feature extraction from a mesh.
//!
//! You need this module to set up a heist (server: [`generate_copies`], [`build_mesh`],
//! [`briefing`]), to show an artifact to the sighted player ([`look`], which carries no trait), to
//! render a copy haptically ([`HapticMesh`], [`Material`]), or to judge a copy from its geometry
//! like the Phantom bot does ([`analyze`], [`matches()`], [`judge`]). Everything here is pure and deterministic
//! for a seed. Coordinates are metres, +y up; see `docs/artifacts.md`.

mod analyze;
mod briefing;
mod generate;
mod kind;
mod lathe;
mod mesh;
mod shapes;

pub use analyze::{MIN_FEATURE_SIZE_M, Observed, PROBE_RAYS, analyze, count_high_runs, judge, matches};
pub use briefing::{Briefing, briefing, number_in_words};
pub use generate::{MIN_COPIES, copy_mesh_seed, generate_copies, target_seed};
pub use kind::{ArtifactKind, ArtifactLook, CopyTraits, Material, MaterialClass, Ridges, look};
pub use mesh::{HapticMesh, MIN_TRIANGLE_AREA_M2, MeshError};
pub use shapes::{AMPHORA_RIDGE_HEIGHT_M, CROWN_POINT_HEIGHT_M, IDOL_NOTCH_DEPTH_M, IDOL_NOTCH_WIDTH_M, build_mesh};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn artifact_data_survives_a_round_trip_through_the_wire_format() {
        let (copies, real) = generate_copies(ArtifactKind::Amphora, 11, 3);
        let mesh = build_mesh(&copies[0], 11);
        let bytes = postcard::to_allocvec(&(&mesh, copies[0].material.material())).expect("encodes");
        assert!(bytes.len() < 64 * 1024, "a workbench mesh is {} bytes", bytes.len());
        let back: (HapticMesh, Material) = postcard::from_bytes(&bytes).expect("decodes");
        assert_eq!(back, (mesh, copies[0].material.material()));
        let b = briefing(&copies[real]);
        let back: Briefing = postcard::from_bytes(&postcard::to_allocvec(&b).expect("encodes")).expect("decodes");
        assert_eq!(back, b);
        let l = look(ArtifactKind::Amphora);
        let back: ArtifactLook = postcard::from_bytes(&postcard::to_allocvec(&l).expect("encodes")).expect("decodes");
        assert_eq!(back, l);
    }
}
