//! Recording a device through the rig and replaying the trace: in lockstep the replay renders the
//! recorded forces to the bit; on the real threads every tick reaches the file; haptic-bench records and
//! replays from the command line.

mod utils;

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use collette::scene;
use forcecomp::Material;
use glam::Vec3;
use haptic_common::{Delegator, ForceTorque, Pose};
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{HapticRig, ObjectSpec, RigConfig, ToolSpec};
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};
use haptico::trace::{self, TraceDevice};
use haptico::{Device, HapticEvents, presets};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rig-record-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

/// The bunny scene with small trees, in lockstep with exact queries, ticked at `times`.
fn run_bunny_scene(device: impl Device, times: &[u64]) -> Vec<ForceTorque> {
    let (_, bunny, gem) = utils::small_bunny_scene();
    let material = Material { stiffness_n_per_m3: 5e8, damping_ns_per_m: 4.0, friction: 0.3, texture: None };
    let mut rig = Lockstep::new(device, ToolSpec::new(gem, material), &RigConfig::default(), 1, None).expect("rig");
    rig.add_object(ObjectSpec { id: 1, tree: bunny, pose: Pose::IDENTITY, material }).expect("bunny");
    times.iter().map(|&t| rig.tick(t)).collect()
}

#[test]
fn a_lockstep_replay_of_a_recorded_trace_renders_the_recorded_forces_to_the_bit() {
    let (bunny_mesh, ..) = utils::small_bunny_scene();
    let keyframes = scene::trajectory(&bunny_mesh).iter().map(|s| Keyframe { t_s: s.time_s, pose: s.tool }).collect();
    let device = SimDevice::new(SimConfig::new(presets::phantom_premium_6dof()), TargetPath::Keyframes(keyframes));
    let path = temp("bunny.trace");
    let (device, writer) = trace::record(device, &path).expect("record");
    // The first 20 s: free, grazing and the deep stretch.
    let times: Vec<u64> = (0..20_000u64).map(|i| i * 1000).collect();
    let rendered = run_bunny_scene(device, &times);
    let stats = writer.finish().expect("written");
    assert_eq!((stats.written, stats.dropped), (20_000, 0));

    let recorded = trace::load_trace(&path).expect("the trace reads back");
    let commands = recorded.commands.clone().expect("a v2 trace carries the commands");
    assert_eq!(commands.len(), 20_000);
    assert!(
        rendered.iter().zip(&commands).all(|(a, b)| a.to_bits() == b.to_bits()),
        "the file holds what was commanded"
    );
    let pushing = commands.iter().filter(|c| c.force.length() > 0.05).count();
    assert!(pushing > 1000, "the path presses into the bunny ({pushing} ticks above 0.05 N)");

    let replayed = TraceDevice::new(presets::phantom_premium_6dof(), recorded.states.clone(), false).expect("trace");
    let times: Vec<u64> = recorded.states.iter().map(|s| s.timestamp_us).collect();
    let again = run_bunny_scene(replayed, &times);
    let differing = again.iter().zip(&commands).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    assert_eq!(differing, 0, "ticks whose replayed force differs from the recorded one");
    std::fs::remove_file(&path).ok();
}

#[test]
fn every_tick_of_the_real_threads_reaches_the_file() {
    let device = SimDevice::new(
        SimConfig::new(presets::touch()),
        TargetPath::line(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.0, -0.002, 0.0), 0.2),
    );
    let path = temp("threads.trace");
    let (device, writer) = trace::record(device, &path).expect("record");
    let tool = ToolSpec::new(utils::ball_tool(), Material::default());
    let rig =
        HapticRig::start(device, tool, RigConfig::default(), HapticEvents::default(), Delegator::new()).expect("rig");
    rig.add_object(utils::slab_object(3)).expect("object");
    std::thread::sleep(Duration::from_millis(500));
    let ran = rig.haptic_telemetry().ticks;
    let recording = rig.stop().expect("the device comes back");
    let ticks = recording.ticks();
    assert!(ticks >= ran && ran > 100, "{ticks} ticks recorded, {ran} run before stopping");
    drop(recording);
    let stats = writer.finish().expect("written");
    assert_eq!(stats.dropped, 0);
    assert_eq!(stats.written, ticks, "one line per tick the haptic thread ran");
    let trace = trace::load_trace(&path).expect("the trace reads back");
    assert_eq!(trace.states.len() as u64, ticks);
    assert!(trace.states.windows(2).all(|w| w[0].timestamp_us <= w[1].timestamp_us));
    let commands = trace.commands.expect("commands");
    assert!(commands.iter().any(|c| c.force.y > 0.0), "the slab pushed the tool back up");
    std::fs::remove_file(&path).ok();
}

fn haptic_bench(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_haptic-bench"))
        .args(["--lockstep", "--seconds", "12", "--bunny-spheres", "1500", "--tool-spheres", "150"])
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("haptic-bench runs");
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "haptic-bench {args:?} failed:\n{stdout}\n{stderr}");
    format!("{stdout}{stderr}")
}

#[test]
fn haptic_bench_records_and_its_lockstep_replay_gives_the_recorded_forces() {
    let path = temp("bench.trace");
    let file = path.to_str().expect("utf-8 path");
    let recorded = haptic_bench(&["--record", file]);
    assert!(recorded.contains("recorded 12000 ticks"), "{recorded}");
    let replayed = haptic_bench(&["--replay", file]);
    assert!(replayed.contains("replay: 12000 of 12000 ticks' forces are the recorded ones to the bit"), "{replayed}");
    std::fs::remove_file(&path).ok();
}

#[test]
fn haptic_bench_says_on_one_line_which_trace_is_bad_and_where() {
    let path = temp("bad.trace");
    std::fs::write(&path, "# haptico trace v2\n0 1 2\n").expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_haptic-bench"))
        .args(["--lockstep", "--replay"])
        .arg(&path)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("haptic-bench runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    let error: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(error.len(), 1, "{stderr}");
    assert!(error[0].contains(&*path.to_string_lossy()) && error[0].contains("line 2"), "{stderr}");
    assert!(!stderr.contains("stack backtrace"), "{stderr}");
    std::fs::remove_file(&path).ok();
}
