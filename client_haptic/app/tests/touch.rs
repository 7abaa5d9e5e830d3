//! The touch bot judges copies from what it feels through the real haptic loop (sim device, collision
//! thread, force stage), never from their data: through the 3-DOF proxy the default Phantom Desktop gets
//! (it renders no torque), and through the volumetric rendering a 6-DOF device gets.

use std::sync::Mutex;
use std::time::Duration;

use client_haptic::explore::feel;
use client_haptic::haptics::{Haptics, HapticsSettings, RenderingChoice};
use haptic_rig::Rendering;
use heist_shared::artifact::{ArtifactKind, build_mesh, generate_copies};
use heist_shared::protocol::{ItemId, WorkbenchCopy};

/// One haptic loop at a time: two would share the two cores and disturb each other's explorations.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn every_copy_is_told_right(rendering: RenderingChoice, expect: Rendering) {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let mut h =
        Haptics::start(HapticsSettings { rendering, ..HapticsSettings::default() }).expect("the haptic loop starts");
    assert_eq!(h.rendering, expect);
    std::thread::sleep(Duration::from_millis(2500)); // the safety layer ramps forces in
    let mut wrong = Vec::new();
    let mut item = 0;
    // Seeds not used to set the thresholds.
    for (kind, seed) in [(ArtifactKind::Crown, 21), (ArtifactKind::Amphora, 22), (ArtifactKind::Idol, 23)] {
        let (copies, _) = generate_copies(kind, seed, 3);
        for traits in &copies {
            item += 1;
            let copy = WorkbenchCopy {
                item: ItemId(item),
                mesh: build_mesh(traits, seed),
                material: traits.material.material(),
            };
            let f = feel(&mut h, &copy, kind).expect("the copy is explored");
            println!("{kind:?} {} {:?}: felt {}", traits.feature_count, traits.material, f.describe());
            if f.feature_count != traits.feature_count || f.material != traits.material {
                let mm: Vec<String> = f.profile.iter().map(|r| format!("{:.1}", r * 1e3)).collect();
                println!("  misjudged; its profile (mm from the axis, poke by poke): {}", mm.join(" "));
                wrong.push((kind, traits.feature_count, traits.material, f.feature_count, f.material));
            }
        }
    }
    h.stop();
    assert!(wrong.is_empty(), "misjudged: {wrong:?}");
}

#[test]
fn the_touch_bot_tells_every_copy_of_each_kind_by_touch_through_the_3dof_proxy() {
    every_copy_is_told_right(RenderingChoice::Auto, Rendering::Proxy);
}

#[test]
fn the_touch_bot_tells_every_copy_of_each_kind_by_touch_through_volumetric_rendering() {
    every_copy_is_told_right(RenderingChoice::Volumetric, Rendering::Coupled);
}

#[test]
fn a_copy_gets_its_surface_grid_with_volumetric_rendering_and_none_through_the_proxy() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let (copies, _) = generate_copies(ArtifactKind::Idol, 3, 3);
    let copy =
        WorkbenchCopy { item: ItemId(1), mesh: build_mesh(&copies[0], 3), material: copies[0].material.material() };
    for (rendering, with_surface) in [(RenderingChoice::Volumetric, true), (RenderingChoice::Proxy, false)] {
        let mut h = Haptics::start(HapticsSettings { rendering, ..HapticsSettings::default() }).expect("starts");
        h.place(&copy);
        let on = (0..600)
            .find_map(|_| {
                std::thread::sleep(Duration::from_millis(50));
                h.poll()
            })
            .expect("the copy reaches the bench within 30 s")
            .expect("the copy is built");
        h.stop();
        assert_eq!(on.surface_bytes.is_some(), with_surface, "{rendering:?}: {on:?}");
        // An idol of about 9 cm at 100 voxels along its longest side: a few megabytes.
        println!("{rendering:?}: {on:?}");
        if let Some(bytes) = on.surface_bytes {
            assert!((1_000_000..50_000_000).contains(&bytes), "{bytes} bytes");
        }
    }
}
