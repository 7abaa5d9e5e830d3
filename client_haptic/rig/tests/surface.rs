//! The tool measured against a watched object's surface grid instead of its tree: set, used, taken away.

mod utils;

use collette::shape::box_buffers;
use collette::{SignedDistanceGrid, TriMesh};
use glam::Vec3;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{RigConfig, RigError, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};
use std::sync::Arc;

/// The ball tool held 2 mm into the slab's top face for half a second, the slab measured by its surface
/// grid from tick `grid_from` to tick `grid_until`; the force at each tick.
fn press(grid_from: u64, grid_until: u64) -> Vec<Vec3> {
    let (v, t) = box_buffers(Vec3::new(0.05, 0.01, 0.05));
    let grid = Arc::new(SignedDistanceGrid::new(&TriMesh::new(v, t).expect("box"), 60).expect("grid"));
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.003, 0.0), Vec3::new(0.0, 0.003, 0.0), 1.0),
    );
    let tool = ToolSpec::new(utils::ball_tool(), forcecomp::Material::default());
    let mut rig = Lockstep::new(device, tool, &RigConfig::default(), 1, None).expect("rig");
    rig.add_object(utils::slab_object(1)).expect("object");
    (0..500)
        .map(|i| {
            if i == grid_from {
                rig.set_surface(1, Some(grid.clone())).expect("surface set");
            }
            if i == grid_until {
                rig.set_surface(1, None).expect("surface taken away");
            }
            rig.tick(i * 1000).force
        })
        .collect()
}

#[test]
fn a_watched_objects_surface_grid_pushes_straight_out_of_a_flat_face_until_it_is_taken_away() {
    let trees = press(u64::MAX, u64::MAX);
    let surface = press(0, u64::MAX);
    let both = press(0, 250);
    assert!(trees[499].y > 0.0 && surface[499].y > 0.0, "pushed up out of the slab: {} / {}", trees[499], surface[499]);
    assert_ne!(trees[249], surface[249], "the grid measures another volume than the tree");
    assert_eq!(&both[..250], &surface[..250], "the same as with the grid while it is set");
    // A flat face pushes straight out along its normal when measured by its surface (the packing's
    // bumpy top pushes sideways too).
    let f = surface[499];
    assert!(f.x.abs().max(f.z.abs()) < 1e-3 * f.y, "straight up from the face: {f}");
    // Taken away: back to the trees' force (the hand still settling: within 5 %).
    let back = both[499];
    assert!(
        (back - trees[499]).length() <= 0.05 * trees[499].length(),
        "the trees' force again: {back} vs {}",
        trees[499]
    );
    assert!((back - f).length() > 0.5 * f.length(), "not the grid's: {back} vs {f}");
}

#[test]
fn an_object_not_watched_has_no_surface_to_set() {
    let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::line(Vec3::ZERO, Vec3::ZERO, 1.0));
    let tool = ToolSpec::new(utils::ball_tool(), forcecomp::Material::default());
    let mut rig = Lockstep::new(device, tool, &RigConfig::default(), 1, None).expect("rig");
    let error = rig.set_surface(7, None).expect_err("no object 7");
    assert!(matches!(error, RigError::UnknownObject(7)) && error.to_string().contains('7'), "{error}");
}
