//! The touch bot judges copies from what it feels through the client's haptic rig (sim device, collision
//! world, force stage), never from their data: through the 3-DOF proxy the default Phantom Desktop gets
//! (it renders no torque), and through the volumetric rendering a 6-DOF device gets.
//!
//! Two clocks:
//! - **Lockstep** (simulated time, [`LockstepHaptics`]): every copy of three kinds, through both
//!   renderings. What these check is the judging — the rig's forces and the bot's thresholds — not the
//!   haptic clock, so the rig is stepped tick by tick on the test's thread, as fast as the machine computes
//!   it, and every run feels the same.
//! - **Real time** ([`RealTimeHaptics`]: the client's `bevy_haptics` set-up, the haptic and collision threads at 1 kHz, the collision step budgeted,
//!   the hand steered across threads): one copy through each rendering, so the loop the player feels is
//!   still explored for real, with its latencies between the threads. These need the machine to
//!   themselves; the lockstep tests beside them would only slow them.

use std::sync::RwLock;

use client_haptic::explore::feel;
use client_haptic::haptics::{HapticsSettings, RenderingChoice};
use client_haptic::touch_bench::{LockstepHaptics, RealTimeHaptics, TouchBench};
use haptic_rig::Rendering;
use heist_shared::artifact::{ArtifactKind, CopyTraits, build_mesh, generate_copies};
use heist_shared::protocol::{ItemId, WorkbenchCopy};

/// Real-time explorations take it for writing (alone on the machine); everything else for reading.
static MACHINE: RwLock<()> = RwLock::new(());

/// The kinds and seeds felt; seeds not used to set the thresholds.
const FELT: [(ArtifactKind, u64); 3] =
    [(ArtifactKind::Crown, 21), (ArtifactKind::Amphora, 22), (ArtifactKind::Idol, 23)];

fn copy_of(traits: &CopyTraits, seed: u64, item: u16) -> WorkbenchCopy {
    WorkbenchCopy { item: ItemId(item), mesh: build_mesh(traits, seed), material: traits.material.material() }
}

/// Feels `copies` on `bench`; what was misjudged.
fn misjudged(
    bench: &mut impl TouchBench,
    copies: &[(ArtifactKind, u64, CopyTraits)],
) -> Vec<(ArtifactKind, u32, String, u32, String)> {
    let mut wrong = Vec::new();
    for (item, (kind, seed, traits)) in (1..).zip(copies) {
        let f = feel(bench, &copy_of(traits, *seed, item), *kind).expect("the copy is explored");
        println!("{kind:?} {} {:?}: felt {}", traits.feature_count, traits.material, f.describe());
        if f.feature_count != traits.feature_count || f.material != traits.material {
            let mm: Vec<String> = f.profile.iter().map(|r| format!("{:.1}", r * 1e3)).collect();
            println!("  misjudged; its profile (mm from the axis, poke by poke): {}", mm.join(" "));
            let (truth, felt) = (format!("{:?}", traits.material), format!("{:?}", f.material));
            wrong.push((*kind, traits.feature_count, truth, f.feature_count, felt));
        }
    }
    wrong
}

/// Every copy of [`FELT`]'s three kinds.
fn every_copy() -> Vec<(ArtifactKind, u64, CopyTraits)> {
    FELT.iter()
        .flat_map(|&(kind, seed)| generate_copies(kind, seed, 3).0.into_iter().map(move |t| (kind, seed, t)))
        .collect()
}

fn every_copy_is_told_right_in_lockstep(rendering: RenderingChoice, expect: Rendering) {
    let _turn = MACHINE.read().unwrap_or_else(|p| p.into_inner());
    let settings = HapticsSettings { rendering, ..HapticsSettings::default() };
    let mut bench = LockstepHaptics::start(settings).expect("the lockstep rig starts");
    assert_eq!(bench.rendering(), expect);
    let copies = every_copy();
    assert_eq!(copies.len(), 9);
    let wrong = misjudged(&mut bench, &copies);
    assert!(wrong.is_empty(), "misjudged: {wrong:?}");
}

fn a_copy_is_told_right_in_real_time(rendering: RenderingChoice, expect: Rendering, kind: ArtifactKind) {
    let _alone = MACHINE.write().unwrap_or_else(|p| p.into_inner());
    let mut h = RealTimeHaptics::start(HapticsSettings { rendering, ..HapticsSettings::default() })
        .expect("the haptic loop starts");
    assert_eq!(h.bench().rendering, expect);
    let copy = every_copy().into_iter().find(|c| c.0 == kind).expect("a copy of the kind");
    let wrong = misjudged(&mut h, &[copy]);
    // The real loop ran: the copy was felt on the haptic thread's clock, with the collision thread's steps.
    let with_copy = h.rates().iter().filter(|w| w.with_copy).count();
    h.stop();
    assert!(with_copy > 0, "no whole second of the loop with the copy on the bench");
    assert!(wrong.is_empty(), "misjudged: {wrong:?}");
}

#[test]
fn the_touch_bot_tells_every_copy_of_each_kind_by_touch_through_the_3dof_proxy_in_lockstep() {
    every_copy_is_told_right_in_lockstep(RenderingChoice::Auto, Rendering::Proxy);
}

#[test]
fn the_touch_bot_tells_every_copy_of_each_kind_by_touch_through_volumetric_rendering_in_lockstep() {
    every_copy_is_told_right_in_lockstep(RenderingChoice::Volumetric, Rendering::Coupled);
}

#[test]
fn the_touch_bot_tells_an_idols_notches_and_material_through_the_real_time_3dof_proxy() {
    a_copy_is_told_right_in_real_time(RenderingChoice::Auto, Rendering::Proxy, ArtifactKind::Idol);
}

#[test]
fn the_touch_bot_tells_a_crowns_points_and_material_through_real_time_volumetric_rendering() {
    a_copy_is_told_right_in_real_time(RenderingChoice::Volumetric, Rendering::Coupled, ArtifactKind::Crown);
}

#[test]
fn a_copy_gets_its_surface_grid_with_volumetric_rendering_and_none_through_the_proxy() {
    let _turn = MACHINE.read().unwrap_or_else(|p| p.into_inner());
    let (copies, _) = generate_copies(ArtifactKind::Idol, 3, 3);
    let copy = copy_of(&copies[0], 3, 1);
    for (rendering, with_surface) in [(RenderingChoice::Volumetric, true), (RenderingChoice::Proxy, false)] {
        let mut h =
            RealTimeHaptics::start(HapticsSettings { rendering, ..HapticsSettings::default() }).expect("starts");
        h.place_and_wait(&copy).expect("the copy is built");
        let on = h.bench().on_bench.clone().expect("the copy is on the bench");
        h.stop();
        assert_eq!(on.surface_bytes.is_some(), with_surface, "{rendering:?}: {on:?}");
        // An idol of about 9 cm at 100 voxels along its longest side: a few megabytes.
        println!("{rendering:?}: {on:?}");
        if let Some(bytes) = on.surface_bytes {
            assert!((1_000_000..50_000_000).contains(&bytes), "{bytes} bytes");
        }
    }
}
