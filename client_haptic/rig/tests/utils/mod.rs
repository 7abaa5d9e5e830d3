//! Shared helpers of the rig's integration tests: small trees built once per test binary.
#![allow(dead_code)]

use std::sync::{Arc, OnceLock};

use collette::shape::{box_buffers, uv_sphere_buffers};
use collette::{BuildOptions, InnerSphereTree, TriMesh};

fn build(mesh: &TriMesh, spheres: usize) -> Arc<InnerSphereTree> {
    let (tree, _) = collette::build(mesh, &BuildOptions::spheres(spheres), &mut |_| {}).expect("tree builds");
    Arc::new(tree)
}

/// A 5 mm-radius ball tool.
pub fn ball_tool() -> Arc<InnerSphereTree> {
    static T: OnceLock<Arc<InnerSphereTree>> = OnceLock::new();
    T.get_or_init(|| {
        let (v, t) = uv_sphere_buffers(0.005, 16, 24);
        build(&TriMesh::new(v, t).expect("sphere mesh"), 200)
    })
    .clone()
}

/// A 10 x 2 x 10 cm box packed with `spheres`, its top face at y = 0.01.
fn slab_of(spheres: usize) -> Arc<InnerSphereTree> {
    let (v, t) = box_buffers(glam::Vec3::new(0.05, 0.01, 0.05));
    build(&TriMesh::new(v, t).expect("box mesh"), spheres)
}

/// A 10 x 2 x 10 cm slab whose top face is at y = 0 (place it with a pose of y = -0.01).
pub fn slab() -> Arc<InnerSphereTree> {
    static T: OnceLock<Arc<InnerSphereTree>> = OnceLock::new();
    T.get_or_init(|| slab_of(1500)).clone()
}

/// The same slab packed finer (6,000 spheres): its top face is flatter (smaller surface spheres).
pub fn fine_slab() -> Arc<InnerSphereTree> {
    static T: OnceLock<Arc<InnerSphereTree>> = OnceLock::new();
    T.get_or_init(|| slab_of(6000)).clone()
}

/// The slab with its top face at y = 0, as object `id` with the default material.
pub fn slab_object(id: u32) -> haptic_rig::ObjectSpec {
    haptic_rig::ObjectSpec {
        id,
        tree: slab(),
        pose: haptic_common::Pose::from_translation(glam::Vec3::new(0.0, -0.01, 0.0)),
        material: forcecomp::Material::default(),
    }
}

/// The benchmark scene with small trees: the bunny's mesh (metres), its tree of 1,500 spheres and the
/// gemstone tool's of 150 (built once per test binary).
pub fn small_bunny_scene() -> (collette::TriMesh, Arc<InnerSphereTree>, Arc<InnerSphereTree>) {
    static T: OnceLock<(collette::TriMesh, Arc<InnerSphereTree>, Arc<InnerSphereTree>)> = OnceLock::new();
    T.get_or_init(|| {
        use collette::scene;
        let bunny_mesh = scene::load_bunny(scene::default_bunny_path()).expect("bunny");
        let bunny = build(&bunny_mesh, 1500);
        let gem = build(&scene::brilliant_cut(scene::TOOL_DIAMETER), 150);
        (bunny_mesh, bunny, gem)
    })
    .clone()
}
