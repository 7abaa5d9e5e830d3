//! The whole per-tick work of both threads (collision step with collette's query, penalty force,
//! coupling, safety, buffers; or, for the 3-DOF proxy, the spheres near the tip and the god-object)
//! neither allocates nor frees once warmed up, on a ribbed slab (the texture force included).

mod utils;

use assert_no_alloc::{AllocDisabler, assert_no_alloc};
use forcecomp::{Material, Texture};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, Rendering, RigConfig, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

#[global_allocator]
static ALLOCATOR: AllocDisabler = AllocDisabler;

#[test]
fn a_steady_state_rig_tick_neither_allocates_nor_frees() {
    steady_state_ticks_do_not_allocate(presets::phantom_premium_6dof(), Rendering::Coupled, false, false);
}

#[test]
fn a_steady_state_proxy_tick_neither_allocates_nor_frees() {
    steady_state_ticks_do_not_allocate(presets::touch(), Rendering::Proxy, false, false);
}

#[test]
fn a_steady_state_tick_pushing_an_object_neither_allocates_nor_frees() {
    // The slab is a 1 kg body the tool pushes: its haptic body moves, its pose goes to the collision
    // stage and its impulses to the game's ring every tick; the tool has its surface shell and the slab
    // its grid, so the collision stage measures the tool's surface (`overlap_shell`).
    steady_state_ticks_do_not_allocate(presets::touch(), Rendering::Coupled, true, false);
    steady_state_ticks_do_not_allocate(presets::touch(), Rendering::Proxy, true, false);
}

#[test]
fn a_steady_state_tick_measuring_both_surfaces_neither_allocates_nor_frees() {
    // The pushed slab with its shell too and the tool with its grid: the collision stage measures both
    // surfaces (`overlap_surfaces_budgeted`).
    steady_state_ticks_do_not_allocate(presets::touch(), Rendering::Coupled, true, true);
}

/// The tool moving into the slab and out; `pushed`: the slab is a body the tool pushes, with its grid,
/// and the tool has its shell; `surfaces`: the slab its shell too and the tool its grid.
fn steady_state_ticks_do_not_allocate(specs: haptico::DeviceSpecs, rendering: Rendering, pushed: bool, surfaces: bool) {
    let device = SimDevice::new(
        SimConfig::new(specs),
        TargetPath::line(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.003, -0.003, 0.002), 2.0),
    );
    let mut tool = ToolSpec::new(utils::ball_tool(), Material::default());
    if pushed {
        // With the slab's grid below, the tool's surface is measured against it (`overlap_shell`).
        let (v, t) = collette::shape::uv_sphere_buffers(0.005, 16, 24);
        let mesh = collette::TriMesh::new(v, t).expect("ball");
        tool = tool.with_shell(std::sync::Arc::new(collette::SurfaceShell::new(&mesh, 0.0005).expect("shell")));
        if surfaces {
            tool = tool.with_surface(std::sync::Arc::new(collette::SignedDistanceGrid::new(&mesh, 32).expect("grid")));
        }
    }
    let config = RigConfig { rendering, ..RigConfig::default() };
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let slab = ObjectSpec {
        id: 1,
        tree: utils::slab(),
        pose: Pose::from_translation(Vec3::new(0.0, -0.01, 0.0)),
        material: Material {
            texture: Some(Texture { axis: Vec3::X, ..Texture::ribs(0.003, 0.0003, 1000.0) }),
            ..Material::default()
        },
    };
    match pushed {
        true => rig.add_pushable(slab, 1.0).expect("pushable"),
        false => rig.add_object(slab).expect("object"),
    }
    if pushed {
        // With its surface grid: the proxy is held on it (read on the haptic thread every tick).
        let (v, t) = collette::shape::box_buffers(Vec3::new(0.05, 0.01, 0.05));
        let grid = collette::SignedDistanceGrid::new(&collette::TriMesh::new(v, t).expect("box"), 32).expect("grid");
        rig.set_surface(1, Some(std::sync::Arc::new(grid))).expect("grid");
        if surfaces {
            let (v, t) = collette::shape::box_buffers(Vec3::new(0.05, 0.01, 0.05));
            let shell = collette::SurfaceShell::new(&collette::TriMesh::new(v, t).expect("box"), 0.002).expect("shell");
            rig.set_object_shell(1, Some(std::sync::Arc::new(shell))).expect("shell");
        }
    }
    let mut t = 0;
    for _ in 0..500 {
        rig.tick(t);
        t += 1000;
    }
    let mut contacts = 0;
    assert_no_alloc(|| {
        for _ in 0..2500 {
            rig.tick(t);
            t += 1000;
            contacts += rig.telemetry().contacts;
        }
    });
    assert!(contacts > 0, "the tool touched the slab during the checked ticks");
    // Both surfaces give one contact (the whole overlap), the tool's columns one per few millimetres.
    assert!(!surfaces || contacts <= 2500, "both surfaces measured: {contacts} contacts in 2,500 ticks");
    if pushed {
        let mut pushes = Vec::new();
        rig.take_pushes(&mut pushes);
        assert!(pushes.first().is_some_and(|p| p.impulse_ns.y < 0.0), "the tool pushed the slab down: {pushes:?}");
    }
}
