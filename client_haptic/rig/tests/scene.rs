//! Objects changed faster than the stages run: what cannot be queued is refused whole, nothing is freed
//! on the real-time side or leaked, and everything replaced or removed comes back to the game thread.

mod utils;

use std::sync::Arc;

use forcecomp::Material;
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, RigConfig, RigError, ToolSpec};
use haptico::presets;
use haptico::sim::{SimConfig, SimDevice, TargetPath};

#[test]
fn objects_replaced_faster_than_the_stages_run_are_refused_whole_and_all_come_back_to_be_freed() {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, -0.002, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.1),
    );
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let mut rig = Lockstep::new(device, tool, &RigConfig::default(), 1, None).expect("rig");
    let slab = utils::slab();
    let before = Arc::strong_count(&slab);
    let (mut accepted, mut adds, mut refused, mut freed, mut t) = (0usize, 0usize, 0usize, 0usize, 0u64);
    for round in 0..20 {
        // Replace object 1 (and sometimes add or remove object 2) until a queue says no.
        loop {
            let x = 0.001 * (accepted % 7) as f32;
            let spec = ObjectSpec {
                id: 1,
                tree: slab.clone(),
                pose: Pose::from_translation(Vec3::X * x),
                ..utils::slab_object(1)
            };
            let remove = accepted % 5 == 4 && round % 2 == 0;
            let result = if remove { rig.remove_object(1) } else { rig.add_object(spec) };
            match result {
                Ok(()) => {
                    accepted += 1;
                    adds += usize::from(!remove);
                }
                Err(RigError::QueueFull(_)) => {
                    refused += 1;
                    break;
                }
                Err(e) => panic!("unexpected {e}"),
            }
        }
        for _ in 0..3 {
            rig.tick(t);
            t += 1000;
        }
        freed += rig.collect_garbage();
        assert!(rig.telemetry().contacts > 0 || round % 2 == 0, "the last slab is felt after round {round}");
    }
    rig.remove_object(1).expect("remove");
    rig.tick(t);
    freed += rig.collect_garbage();
    assert_eq!(refused, 20, "every round ended on a full queue");
    assert!(accepted > 100, "{accepted} changes queued");
    assert_eq!(rig.collision_leaks(), 0, "the collision stage never leaked");
    assert_eq!(freed, adds, "every object added was handed back by the force stage once (replaced or removed)");
    assert_eq!(Arc::strong_count(&slab), before, "every tree handed to the stages was freed here");
}
