//! A scene of 256 objects in the rig, the tool sweeping through them: the objects the telemetry says
//! the tool touches are exactly those a direct query of every pair finds on the same poses, with the
//! same overlap volumes.

mod utils;

use std::sync::Arc;

use collette::shape::box_buffers;
use collette::{Budget, BuildOptions, ContactSet, InnerSphereTree, QueryWorkspace, TriMesh, overlap_budgeted};
use forcecomp::Material;
use glam::{Quat, Vec3};
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{MAX_OBJECTS, ObjectSpec, Rendering, RigConfig, RigError, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

#[test]
fn a_tool_sweeping_through_256_objects_touches_exactly_what_every_pair_queried_directly_touches() {
    let (v, t) = box_buffers(Vec3::splat(0.004));
    let cube: Arc<InnerSphereTree> = Arc::new(
        collette::build(&TriMesh::new(v, t).expect("box"), &BuildOptions::spheres(60), &mut |_| {}).expect("tree").0,
    );
    // The 5 mm ball crosses a 16 × 16 grid of 8 mm cubes 12 mm apart (turned a little each) diagonally.
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(-0.1, 0.0, -0.1), Vec3::new(0.1, 0.0, 0.1), 1.0),
    );
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    // Contacts reported, no contact force: the tool is the device, wherever the hand takes it.
    let config = RigConfig { rendering: Rendering::Off, ..RigConfig::default() };
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let poses: Vec<Pose> = (0..MAX_OBJECTS)
        .map(|i| {
            let (col, row) = ((i % 16) as f32, (i / 16) as f32);
            let at = Vec3::new(-0.09 + col * 0.012, 0.0, -0.09 + row * 0.012);
            Pose::new(at, Quat::from_rotation_y(i as f32 * 0.3))
        })
        .collect();
    for (i, pose) in poses.iter().enumerate() {
        let spec = ObjectSpec { id: i as u32, tree: cube.clone(), pose: *pose, material: Material::default() };
        rig.add_object(spec).expect("room for 256 objects");
    }
    let more = ObjectSpec { id: 999, tree: cube.clone(), pose: Pose::IDENTITY, material: Material::default() };
    assert!(matches!(rig.add_object(more), Err(RigError::TooManyObjects(MAX_OBJECTS))));

    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let (mut previous, mut touches, mut ever) = (None, 0, std::collections::BTreeSet::new());
    for tick in 0..1100u64 {
        rig.tick(tick * 1000);
        let telemetry = rig.telemetry();
        // This tick's contacts come from the collision step before it, on the tool's pose of the tick
        // before.
        if let Some(tool_pose) = previous {
            let mut want = Vec::new();
            for (i, pose) in poses.iter().enumerate() {
                let result = overlap_budgeted(
                    &utils::ball_tool(),
                    &tool_pose,
                    &cube,
                    pose,
                    Budget::Unlimited,
                    &mut ws,
                    &mut set,
                );
                if !set.is_empty() {
                    want.push((i as u32, result.total_volume));
                }
            }
            let mut got: Vec<(u32, f32)> =
                telemetry.objects().iter().filter(|c| c.touching).map(|c| (c.id, c.volume)).collect();
            got.sort_by_key(|c| c.0);
            assert_eq!(got, want, "tick {tick}");
            touches += got.len();
            ever.extend(got.iter().map(|c| c.0));
        }
        previous = Some(telemetry.tool_pose);
    }
    assert!(ever.len() >= 12, "the sweep crosses the grid: it touched {} objects ({touches} contacts)", ever.len());
}
