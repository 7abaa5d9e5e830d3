//! Every example runs headless (`--headless --seconds N`: the simulated hand follows the example's
//! script) and ends with one JSON line whose figures are checked: it touched what its path touches,
//! forces stayed within the device's peak and were numbers, and both threads kept their rate.
//!
//! The rate bounds here are a median 100 ms window at 800 Hz or more and nine windows in ten at 500 Hz or
//! more, looser than the 950 Hz in every window the issue asks of a release build: these are debug builds
//! of the examples on a shared two-core machine, beside other tests, where one window in thirty can stall
//! (CI saw one at 360 Hz in a run whose median was 1 kHz). Release rates, slowest window included, are
//! measured by the examples in release and by `haptic-bench` (docs/haptics.md). One example runs at a time.

use std::process::Command;
use std::sync::Mutex;
use std::time::{Duration, Instant};

mod support;

use support::example;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Runs `name` headless for `seconds` and returns its JSON line.
fn run(name: &str, seconds: f32) -> serde_json::Value {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let start = Instant::now();
    let out = Command::new(example(name))
        .args(["--headless", "--seconds", &seconds.to_string()])
        .env("RUST_LOG", "warn")
        .output()
        .expect("the example starts");
    assert!(start.elapsed() < Duration::from_secs_f32(seconds + 60.0), "{name} took {:?}", start.elapsed());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{name} failed: {}\n{stdout}", String::from_utf8_lossy(&out.stderr));
    let last = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(last).unwrap_or_else(|e| panic!("{name}'s last line is not JSON ({e}): {last:?}"))
}

fn number(report: &serde_json::Value, key: &str) -> f64 {
    report[key].as_f64().unwrap_or_else(|| panic!("{key} is not a number in {report}"))
}

/// Checks what every example's line must show; `peak_n` is the device's peak force.
fn check(report: &serde_json::Value, name: &str, seconds: f64, peak_n: f64, collision: bool) {
    assert_eq!(report["example"], name);
    assert_eq!(number(report, "seconds"), seconds);
    assert_eq!(report["non_finite"], false, "{report}");
    assert!(number(report, "contacts") > 0.0, "the path touches: {report}");
    let force = number(report, "max_force_n");
    assert!(force > 0.05 && force <= peak_n + 1e-3, "a force within the device's peak: {report}");
    // The safety layer moves the force by at most 500 N/s × the tick's interval: 0.5 N a tick at 1 kHz,
    // more on a late tick (a busy machine), so the rate is what is bounded (device time and the safety
    // layer's clock may differ by a little).
    assert!(number(report, "max_force_rate_n_per_s") <= 550.0, "{report}");
    let threads: &[&str] = if collision { &["haptic", "collision"] } else { &["haptic"] };
    for thread in threads {
        assert!(number(report, &format!("{thread}_hz_median")) >= 800.0, "{thread}: {report}");
        assert!(number(report, &format!("{thread}_hz_p10")) >= 500.0, "{thread}: {report}");
    }
    assert!(number(report, "ticks") >= 0.5 * 1000.0 * seconds, "{report}");
}

#[test]
fn touch_bunny_strokes_the_bunny_through_the_3dof_proxy_headless() {
    let report = run("touch_bunny", 5.0);
    check(&report, "touch_bunny", 5.0, 7.9, true);
}

#[test]
fn scene_file_sets_up_the_tool_and_the_bunny_from_a_scene_file_and_strokes_it_headless() {
    // No set-up code: the tool, the bunny's tree source, material and place all come from the file.
    let report = run("scene_file", 5.0);
    check(&report, "scene_file", 5.0, 7.9, true);
}

#[test]
fn custom_force_renders_its_own_floor_and_still_hears_of_contacts_headless() {
    let report = run("custom_force", 3.0);
    check(&report, "custom_force", 3.0, 3.3, true);
}

#[test]
fn a_bad_argument_is_refused_on_one_line() {
    let out = Command::new(example("touch_bunny")).arg("--fast").output().expect("starts");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--fast") && stderr.contains("--headless"), "{stderr}");
}

#[test]
fn effects_visits_a_spring_a_pool_a_plate_and_lands_on_a_magnetic_bunny_headless() {
    let report = run("effects", 7.0);
    check(&report, "effects", 7.0, 3.3, true);
}

#[test]
fn six_dof_tool_presses_the_gem_into_the_bunny_by_both_surfaces_and_feels_a_torque_headless() {
    let report = run("six_dof_tool", 5.0);
    check(&report, "six_dof_tool", 5.0, 8.5, true);
    assert!(number(&report, "max_torque_nm") > 0.0, "the gem's off-centre contact twists it: {report}");
    // Both have their grid and shell: a step measures the whole overlap from both surfaces, one contact
    // (the gem's surface alone gives one a few millimetres: 77 steps of 1,655 had one; a step whose
    // budget runs out falls back on it).
    let (touching, whole) = (number(&report, "steps_in_contact"), number(&report, "steps_one_contact"));
    assert!(touching >= 500.0 && whole >= 0.75 * touching, "both surfaces measured: {report}");
}

#[test]
fn moving_platform_carries_the_resting_tool_while_the_game_slides_it_headless() {
    let report = run("moving_platform", 5.0);
    check(&report, "moving_platform", 5.0, 3.3, true);
    // The hand goes down once the platform's tree is built (a few tenths of a second) and lands 0.5 s
    // later; the contact goes on, frame after frame, while the platform slides.
    assert!(number(&report, "frames_on_platform") >= 100.0, "the tool rides the platform: {report}");
}

#[test]
fn push_box_pushes_an_avian_box_along_the_table_headless() {
    // The script starts once the box's tree is built and takes 3.1 s.
    let report = run("push_box", 5.0);
    check(&report, "push_box", 5.0, 3.3, true);
    // The hand goes 6.5 cm past the box's face along +x: avian's box goes most of that way, straight,
    // and stays on the table.
    let x = number(&report, "box_moved_x_m");
    assert!((0.03..0.08).contains(&x), "pushed along +x: {report}");
    assert!(number(&report, "box_moved_z_m").abs() < 0.01, "straight: {report}");
    assert!((number(&report, "box_height_m") - 0.02).abs() < 0.005, "on the table: {report}");
    assert!(number(&report, "impulse_x_ns") > 0.0, "the pushes went to avian: {report}");
}
