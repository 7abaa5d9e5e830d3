//! Objects the game moves at its own frame rate: given with their times (`set_object_pose_at`), the
//! 1 kHz threads move them smoothly between frames and feel their velocity; placed every frame
//! (`set_object_pose`), they jump once a frame.

mod utils;

use std::sync::Arc;

use collette::shape::box_buffers;
use collette::{SignedDistanceGrid, TriMesh};
use forcecomp::Material;
use glam::{Quat, Vec3};
use haptic_common::Pose;
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{ObjectSpec, Rendering, RigConfig, ToolSpec};
use haptico::mock::MockDevice;

/// A 60 Hz game's frame period, µs.
const FRAME_US: u64 = 16_667;

/// The device stays at the scene's origin; the tool is the device itself (no coupling), so the
/// contact force depends only on where the object is and how it moves.
fn rig() -> Lockstep<MockDevice> {
    let (device, _log) = MockDevice::touch();
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let config = RigConfig { rendering: Rendering::Direct, ..RigConfig::default() };
    let mut rig = Lockstep::new(device, tool, &config, 1, None).expect("rig");
    let slab = ObjectSpec { pose: slab_at(0), ..utils::slab_object(1) };
    // (placed at its first pose; the game then moves it)
    rig.add_object(slab).expect("slab");
    let (v, t) = box_buffers(Vec3::new(0.05, 0.01, 0.05));
    let grid = SignedDistanceGrid::new(&TriMesh::new(v, t).expect("box"), 64).expect("grid");
    rig.set_surface(1, Some(Arc::new(grid))).expect("grid");
    rig
}

/// The slab tilted 3° and sliding along x at 0.5 m/s: under the tool's ball its top face rises from
/// 0.5 mm into the ball to 4.2 mm in 140 ms.
fn slab_at(t_us: u64) -> Pose {
    let x = -0.04 + 0.5 * t_us as f32 * 1e-6;
    let tilt = -3f32.to_radians();
    let y = (0.001 - 0.015 - x * tilt.sin()) / tilt.cos();
    Pose::new(Vec3::new(x, y, 0.0), Quat::from_rotation_z(tilt))
}

/// Runs 150 ms, telling the rig where the slab is once a frame with `send`; returns the largest change
/// of the contact force between two ticks in contact, and the largest force.
fn largest_step(send: impl Fn(&mut Lockstep<MockDevice>, Pose, u64)) -> (f32, f32) {
    let mut rig = rig();
    let mut samples = Vec::new();
    for t_us in (0..150_000u64).step_by(1000) {
        if t_us % FRAME_US < 1000 {
            let frame_us = t_us / FRAME_US * FRAME_US;
            send(&mut rig, slab_at(frame_us), frame_us);
        }
        rig.tick(t_us);
        rig.drain_force_samples(&mut samples);
    }
    // Between two ticks in contact: the first touch of a surface coming at the tool is a step of
    // Eq. 1's damping (its damping does not scale with the overlap) however the object is moved.
    let step = samples
        .windows(2)
        .filter(|w| w[0].contacts > 0 && w[1].contacts > 0)
        .map(|w| (w[1].contact_force - w[0].contact_force).length())
        .fold(0.0f32, f32::max);
    (step, samples.iter().map(|s| s.contact_force.length()).fold(0.0, f32::max))
}

#[test]
fn an_object_moved_by_60_hz_poses_with_their_times_pushes_without_a_step_each_frame() {
    let (placed, placed_peak) = largest_step(|rig, pose, _| rig.set_object_pose(1, pose).expect("placed"));
    let (tracked, tracked_peak) =
        largest_step(|rig, pose, t_us| rig.set_object_pose_at(1, pose, t_us).expect("tracked"));
    assert!(placed_peak > 0.2 && tracked_peak > 0.2, "the slab presses into the ball: {placed_peak} {tracked_peak}");
    assert!(
        tracked * 5.0 <= placed,
        "the largest force step between ticks shrinks 5× or more: {tracked:.4} N tracked, {placed:.4} N placed"
    );
}

#[test]
fn an_object_rising_into_the_tool_pushes_harder_than_one_resting_at_the_same_place_by_its_damping() {
    // The slab's top face rises into the ball at 50 mm/s; a second rig has it placed, at rest, where the
    // first one's track puts it on each tick.
    let speed = 0.05;
    let level = |t_us: u64| Pose::from_translation(Vec3::new(0.0, -0.0135 + speed * t_us as f32 * 1e-6, 0.0));
    let (mut moving, mut resting) = (rig(), rig());
    let mut track = collette::pipeline::PoseTrack::new(RigConfig::default().tracks);
    let (mut pushes, mut samples) = (Vec::new(), Vec::new());
    for t_us in (0..60_000u64).step_by(1000) {
        if t_us % FRAME_US < 1000 {
            let frame_us = t_us / FRAME_US * FRAME_US;
            moving.set_object_pose_at(1, level(frame_us), frame_us).expect("tracked");
            track.push(level(frame_us), frame_us);
        }
        let now = track.at(t_us).expect("a sample").pose;
        resting.set_object_pose(1, now).expect("placed");
        moving.tick(t_us);
        resting.tick(t_us);
        let (m, r) = (moving.telemetry().objects()[0], resting.telemetry().objects()[0]);
        if t_us >= 40_000 {
            assert_eq!(m.volume, r.volume, "at {t_us} µs both slabs are at the same place");
            pushes.push(m.force.y - r.force.y);
        }
        moving.drain_force_samples(&mut samples);
        resting.drain_force_samples(&mut samples);
    }
    let damping = Material::default().combine(&Material::default()).damping_ns_per_m;
    let want = speed * damping;
    for push in pushes {
        assert!((push - want).abs() <= 0.1 * want, "the damping of 50 mm/s: {push} N, not {want} N");
    }
}

#[test]
fn an_object_moved_once_with_its_time_glides_there_from_where_it_was_placed() {
    // The level slab 2 mm into the ball, then told once (at 50 ms) that it is 1 mm higher: placed, the
    // overlap jumps on the next tick; sent with its time, it grows over the track's 20 ms.
    let level = |y: f32| Pose::from_translation(Vec3::new(0.0, y, 0.0));
    let run = |tracked: bool| {
        let mut rig = rig();
        rig.set_object_pose(1, level(-0.013)).expect("placed");
        let mut volumes = Vec::new();
        for t_us in (0..120_000u64).step_by(1000) {
            if t_us == 50_000 {
                match tracked {
                    true => rig.set_object_pose_at(1, level(-0.012), t_us).expect("tracked"),
                    false => rig.set_object_pose(1, level(-0.012)).expect("placed"),
                }
            }
            rig.tick(t_us);
            if t_us >= 40_000 {
                volumes.push(rig.telemetry().objects().first().map_or(0.0, |c| c.volume));
            }
        }
        let step = volumes.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0f32, f32::max);
        (step, *volumes.last().expect("ticks"))
    };
    let ((placed, placed_end), (glided, glided_end)) = (run(false), run(true));
    assert!(placed_end > 0.0 && placed_end == glided_end, "both end in the same place: {placed_end} {glided_end}");
    assert!(glided * 5.0 <= placed, "no jump: {glided:e} m³ a tick against {placed:e} m³");
}
