//! The tool measured against a watched object's surface grid instead of its tree: set, used, taken away.

mod utils;

use collette::shape::box_buffers;
use collette::shape::uv_sphere_buffers;
use collette::{SignedDistanceGrid, SurfaceShell, TriMesh};
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

/// The ball tool (with its surface shell from `shell_from` to `shell_until`) held 2 mm into the slab,
/// measured by the slab's surface grid; the force at each tick.
fn press_with_shell(shell_from: u64, shell_until: u64) -> Vec<Vec3> {
    let (v, t) = box_buffers(Vec3::new(0.05, 0.01, 0.05));
    let grid = Arc::new(SignedDistanceGrid::new(&TriMesh::new(v, t).expect("box"), 60).expect("grid"));
    let (v, t) = uv_sphere_buffers(0.005, 16, 24);
    let shell = Arc::new(SurfaceShell::new(&TriMesh::new(v, t).expect("ball"), 0.0005).expect("shell"));
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.003, 0.0), Vec3::new(0.0, 0.003, 0.0), 1.0),
    );
    let spheres = ToolSpec::new(utils::ball_tool(), forcecomp::Material::default());
    let mut rig = Lockstep::new(device, spheres.clone(), &RigConfig::default(), 1, None).expect("rig");
    rig.add_object(utils::slab_object(1)).expect("object");
    rig.set_surface(1, Some(grid)).expect("surface set");
    (0..500)
        .map(|i| {
            if i == shell_from {
                rig.set_tool(spheres.clone().with_shell(shell.clone())).expect("tool with its shell");
            }
            if i == shell_until {
                rig.set_tool(spheres.clone()).expect("tool without");
            }
            rig.tick(i * 1000).force
        })
        .collect()
}

#[test]
fn a_tool_with_its_surface_shell_is_measured_by_its_surface_until_it_is_replaced_by_one_without() {
    let spheres = press_with_shell(u64::MAX, u64::MAX);
    let shell = press_with_shell(0, u64::MAX);
    let both = press_with_shell(0, 250);
    let f = shell[499];
    assert!(f.y > 0.0 && spheres[499].y > 0.0, "pushed up: {f} / {}", spheres[499]);
    // The shell's columns all stand on the flat face: straight up.
    assert!(f.x.abs().max(f.z.abs()) < 1e-3 * f.y, "straight up from the face: {f}");
    assert_ne!(f, spheres[499], "the surface measures another volume than the spheres");
    assert_eq!(&both[..250], &shell[..250], "the same as with the shell while it is set");
    let back = both[499];
    assert!((back - spheres[499]).length() <= 0.05 * spheres[499].length(), "the spheres' again: {back}");
}

/// The overlap volume (m³) and the tool's height (m) after 300 ticks of the ball tool held 4.5 mm into
/// a 4 mm plate (past its middle), the plate with its grid and shell, the tool with its shell and, when
/// `tool_grid`, its grid.
fn press_through_plate(tool_grid: bool) -> (f32, f32) {
    let (v, t) = box_buffers(Vec3::new(0.03, 0.002, 0.03));
    let plate = TriMesh::new(v, t).expect("plate");
    let (plate_tree, _) =
        collette::build(&plate, &collette::BuildOptions::spheres(600), &mut |_| {}).expect("plate tree");
    let (v, t) = uv_sphere_buffers(0.005, 48, 96);
    let ball = TriMesh::new(v, t).expect("ball");
    let mut tool = ToolSpec::new(utils::ball_tool(), forcecomp::Material::default())
        .with_shell(Arc::new(SurfaceShell::new(&ball, 0.0005).expect("shell")));
    if tool_grid {
        tool = tool.with_surface(Arc::new(SignedDistanceGrid::new(&ball, 64).expect("ball grid")));
    }
    let centre = Vec3::new(0.001, 0.0025, -0.002);
    let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::line(centre, centre, 1.0));
    let mut rig = Lockstep::new(device, tool, &RigConfig::default(), 1, None).expect("rig");
    let object = haptic_rig::ObjectSpec {
        id: 1,
        tree: Arc::new(plate_tree),
        pose: haptic_common::Pose::IDENTITY,
        material: forcecomp::Material::default(),
    };
    rig.add_object(object).expect("plate");
    rig.set_surface(1, Some(Arc::new(SignedDistanceGrid::new(&plate, 128).expect("plate grid")))).expect("grid");
    rig.set_object_shell(1, Some(Arc::new(SurfaceShell::new(&plate, 0.001).expect("plate shell")))).expect("shell");
    for i in 0..300 {
        rig.tick(i * 1000);
    }
    let telemetry = rig.telemetry();
    let contact = telemetry.objects()[0];
    (contact.volume, telemetry.tool_pose.translation.y)
}

#[test]
fn a_tool_with_its_shell_and_grid_measures_both_surfaces_past_the_middle_of_a_thin_plate() {
    // The ball's cap under the plate's top face (y = 2 mm), for the ball's centre at `y`.
    let cap = |y: f32| {
        let (r, h) = (0.005f32, 0.002 - (y - 0.005));
        std::f32::consts::PI * h * h * (3.0 * r - h) / 3.0
    };
    let (both, y) = press_through_plate(true);
    assert!(y - 0.005 < -0.001, "the ball's bottom past the plate's middle: centre at {y}");
    assert!((both / cap(y) - 1.0).abs() < 0.03, "both surfaces: {both} m³ against the cap's {}", cap(y));
    // The tool's columns alone run to the plate's far face.
    let (columns, y) = press_through_plate(false);
    assert!((columns / cap(y) - 1.0).abs() > 0.1, "the columns alone: {columns} m³ against {}", cap(y));
}
