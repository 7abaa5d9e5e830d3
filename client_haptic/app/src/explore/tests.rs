use super::*;

/// Radius of the frictionless vertical cylinder the tests' idol is, m: the look's.
fn body_radius() -> f32 {
    0.5 * artifact::look(ArtifactKind::Idol).size_m[0]
}

/// Depth of the tests' idol's one notch, 5 mm deep, within 0.55 rad of π (17 of its 96 pokes), m.
fn notch(p: Vec3) -> f32 {
    let angle = (-p.z).atan2(p.x).rem_euclid(TAU);
    if (angle - std::f32::consts::PI).abs() < 0.55 { 0.005 } else { 0.0 }
}

/// Where the tests' hand starts: above where the pokes start.
fn start() -> Vec3 {
    let (y, r_out, ..) = ring(ArtifactKind::Idol);
    Vec3::new(r_out, y + 0.05, 0.0)
}

/// Runs an exploration of an idol (a cylinder of [`body_radius`] with a [`notch`], 200 N/m) on a hand that follows
/// its goal exactly, with frames every 8 ms; `tick(t_us)` says whether the haptic loop ticks at
/// `t_us` and how old its contact data is. Returns the findings and the stages seen, with the time
/// each began.
fn run(tick: impl FnMut(u64) -> Option<u32>) -> (Findings, Vec<(Stage, u64)>) {
    let (findings, stages, _) = run_held(tick, |_, _| None);
    (findings, stages)
}

/// [`run`], with the tool held at `held(exploration, t_us)` instead of the goal when that says so;
/// also returns the exploration.
fn run_held(
    tick: impl FnMut(u64) -> Option<u32>,
    held: impl Fn(&Exploration, u64) -> Option<Vec3>,
) -> (Findings, Vec<(Stage, u64)>, Exploration) {
    run_from(start(), tick, held)
}

/// [`run_held`] with the hand starting at `hand`.
fn run_from(
    hand: Vec3,
    mut tick: impl FnMut(u64) -> Option<u32>,
    held: impl Fn(&Exploration, u64) -> Option<Vec3>,
) -> (Findings, Vec<(Stage, u64)>, Exploration) {
    let mut ex = Exploration::new(ArtifactKind::Idol, 0, hand);
    let mut stages = vec![(ex.stage, 0)];
    let mut samples = Vec::new();
    for frame in 1..40_000u64 {
        let now = frame * 8_000;
        samples.clear();
        for t_us in (now - 8_000..now).step_by(1_000) {
            if let Some(data_age_us) = tick(t_us) {
                let tool_position = held(&ex, t_us).unwrap_or(ex.goal().sample(t_us).translation);
                let out = Vec3::new(tool_position.x, 0.0, tool_position.z);
                let depth = (body_radius() - notch(out) - out.length()).max(0.0);
                let contact_force = out.normalize_or_zero() * 200.0 * depth;
                samples.push(ForceSample { t_us, tool_position, contact_force, data_age_us, ..ForceSample::default() });
            }
        }
        if ex.step(now, &samples) {
            stages.push((ex.stage, ex.stage_start_us));
            let (_, r_out, ..) = ring(ArtifactKind::Idol);
            if matches!(ex.stage, Stage::Return | Stage::Round) {
                for dt in (0..3_000_000).step_by(100_000) {
                    let p = ex.goal().sample(ex.stage_start_us + dt).translation;
                    assert!((Vec3::new(p.x, 0.0, p.z).length() - r_out).abs() < 1e-4, "round the ring");
                }
            }
            if ex.stage == Stage::Round {
                // It ends at the press's angle: the approach then only moves along the axis.
                let end = ex.goal().sample(ex.stage_end_us).translation;
                let angle = (-end.z).atan2(end.x).rem_euclid(TAU);
                let off = (angle - ex.press_angle.rem_euclid(TAU) + 3.0 * std::f32::consts::PI).rem_euclid(TAU)
                    - std::f32::consts::PI;
                assert!(off.abs() < 1e-3, "ends {off} rad from the press's angle");
            }
        }
        if let Some(f) = ex.findings() {
            return (f.clone(), stages, ex);
        }
    }
    panic!("the exploration never ended: {stages:?}");
}

#[test]
fn an_undisturbed_exploration_takes_one_attempt_and_one_press() {
    let (findings, stages) = run(|_| Some(1_000));
    assert_eq!((findings.attempts, findings.disturbed, findings.presses), (1, false, 1), "{stages:?}");
    assert!(!stages.iter().any(|(s, _)| *s == Stage::Retreat), "{stages:?}");
    assert!(stages.iter().any(|(s, _)| *s == Stage::Round), "goes round the ring to press: {stages:?}");
    assert!(findings.stroke_contact > 0.9, "{findings:?}");
    let r = body_radius();
    let (body, notch) = (r - 0.001..r, r - 0.006..r - 0.005);
    let at = |k: usize| {
        let phi = TAU * k as f32 / IDOL_TAPS as f32;
        Vec3::new(phi.cos(), 0.0, -phi.sin())
    };
    let felt = |k: usize| if super::tests::notch(at(k)) > 0.0 { notch.clone() } else { body.clone() };
    assert!(findings.profile.iter().enumerate().all(|(k, p)| felt(k).contains(p)), "{findings:?}");
    assert_eq!(findings.feature_count, 1, "{findings:?}");
    assert!(findings.stiffness_n_per_m > 150.0 && findings.stiffness_n_per_m < 250.0, "{findings:?}");
}

#[test]
fn the_hand_goes_round_the_copy_to_the_first_poke_never_across_it() {
    let (y, r_out, ..) = ring(ArtifactKind::Idol);
    let radial = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
    // Where the last exploration ended: out from a press on the far side, a little lower.
    let far = Vec3::new(-(r_out + 0.02), y - 0.01, 0.003);
    let nearest = std::cell::Cell::new(f32::INFINITY);
    let first = std::cell::Cell::new(None);
    let held = |ex: &Exploration, t| {
        if matches!(ex.stage, Stage::Arrive | Stage::Circle | Stage::Settle) {
            let p = ex.goal.sample(t).translation;
            first.set(first.get().or(Some(p)));
            nearest.set(nearest.get().min(radial(p)));
        }
        None
    };
    let (findings, stages, _) = run_from(far, |_| Some(1_000), held);
    assert!(first.get().is_some_and(|p| p.distance(far) < 1e-4), "starts where the hand is: {:?}", first.get());
    assert!(nearest.get() > r_out - 1e-4, "{} m from the axis, the ring is at {r_out} m", nearest.get());
    let order: Vec<Stage> = stages.iter().map(|(s, _)| *s).take(4).collect();
    assert_eq!(order, [Stage::Arrive, Stage::Circle, Stage::Settle, Stage::Taps]);
    assert_eq!((findings.feature_count, findings.attempts), (1, 1), "{findings:?}");
    // A hand inside the ring goes straight out first.
    let near = Vec3::new(0.0, y, 0.02);
    let ex = Exploration::new(ArtifactKind::Idol, 0, near);
    let out = ex.goal.sample(1_000_000).translation;
    assert!((radial(out) - r_out).abs() < 1e-5 && out.x.abs() < 1e-6 && out.y == y, "{out:?}");
}

#[test]
fn a_first_stroke_that_met_nothing_explores_again() {
    let (_, r_out, ..) = ring(ArtifactKind::Idol);
    // The stylus stays out through the first exploration's stroke.
    let held = |ex: &Exploration, _| {
        (matches!(ex.stage, Stage::SlideDown | Stage::SlideUp) && ex.attempts == 1)
            .then_some(Vec3::new(r_out, 0.0, 0.0))
    };
    let (findings, stages, _) = run_held(|_| Some(1_000), held);
    assert_eq!((findings.attempts, findings.unconfirmed, findings.presses), (2, 1, 1), "{stages:?}");
    assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Taps).count(), 2, "poked again: {stages:?}");
    assert_eq!(findings.feature_count, 1);
    assert!(findings.stroke_contact > 0.9, "the second stroke touched: {findings:?}");
    assert!(findings.describe().contains("1 with a first stroke that met nothing"), "{}", findings.describe());
}

#[test]
fn on_the_last_exploration_a_stroke_that_met_nothing_is_pressed_again_deeper() {
    let (_, r_out, ..) = ring(ArtifactKind::Idol);
    let radial = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
    // The stylus stays out through each exploration's first stroke; how deep each press of the last
    // exploration reaches for is noted.
    let deepest = std::cell::RefCell::new([f32::INFINITY; ATTEMPTS as usize]);
    let held = |ex: &Exploration, t| {
        if ex.stage == Stage::Press && ex.attempts == ATTEMPTS {
            let d = &mut deepest.borrow_mut()[ex.presses as usize - 1];
            *d = d.min(radial(ex.goal.sample(t).translation));
        }
        (matches!(ex.stage, Stage::SlideDown | Stage::SlideUp) && ex.presses == 1).then_some(Vec3::new(r_out, 0.0, 0.0))
    };
    let (findings, stages, ex) = run_held(|_| Some(1_000), held);
    let deepest = deepest.into_inner();
    assert!((deepest[0] - (ex.surface - REACH_M)).abs() < 1e-4, "{deepest:?}");
    assert!((deepest[0] - deepest[1] - DEEPER_M).abs() < 1e-4, "the second press reaches 2 mm deeper: {deepest:?}");
    assert_eq!((findings.attempts, findings.unconfirmed, findings.presses), (ATTEMPTS, ATTEMPTS - 1, 2));
    assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Press).count(), ATTEMPTS as usize + 1, "{stages:?}");
    assert!(findings.stroke_contact > 0.9, "the second stroke touched: {findings:?}");
    assert!(findings.describe().contains("2 presses"), "{}", findings.describe());
    let press = ex.goal.sample(u64::MAX);
    assert!(radial(press.translation) > r_out, "backed out at the end: {press:?}");
    assert!((ex.surface - body_radius()).abs() < 0.001, "the surface where the cylinder is: {}", ex.surface);
    // A stroke that never meets anything ends after the last press, friction unknown (0).
    let never = |ex: &Exploration, _| {
        matches!(ex.stage, Stage::SlideDown | Stage::SlideUp).then_some(Vec3::new(r_out, 0.0, 0.0))
    };
    let (findings, stages, _) = run_held(|_| Some(1_000), never);
    assert_eq!((findings.presses, findings.stroke_contact, findings.friction), (ATTEMPTS, 0.0, 0.0), "{stages:?}");
}

#[test]
fn a_missed_poke_where_the_press_goes_takes_the_surface_from_the_poke_before() {
    let (_, r_out, ..) = ring(ArtifactKind::Idol);
    // The press goes to the first poke's angle, opposite the notch; the stylus stays out through
    // that poke.
    let poke = |ex: &Exploration| ex.taps_start_us..ex.taps_start_us + (TAP_S * 1e6) as u64;
    let held =
        |ex: &Exploration, t| (ex.stage == Stage::Taps && poke(ex).contains(&t)).then_some(Vec3::new(r_out, 0.0, 0.0));
    let (findings, _, ex) = run_held(|_| Some(1_000), held);
    assert!(ex.touches()[0].is_none() && ex.press_angle == 0.0, "{findings:?}");
    assert!((ex.surface - body_radius()).abs() < 0.001, "the surface where the cylinder is: {}", ex.surface);
    assert_eq!(findings.presses, 1);
}

#[test]
fn a_stall_during_the_taps_starts_over_once_the_forces_are_whole_again() {
    // The process is not scheduled for 1.5 s, 5 s in (during the taps).
    let (findings, stages) = run(|t| (!(5_000_000..6_500_000).contains(&t)).then_some(1_000));
    assert_eq!((findings.attempts, findings.disturbed), (2, false), "{stages:?}");
    let at = |stage| stages.iter().filter(|(s, _)| *s == stage).map(|(_, t)| *t).collect::<Vec<_>>();
    let retreat = at(Stage::Retreat);
    assert_eq!(retreat.len(), 1, "{stages:?}");
    assert!(retreat[0] < 6_600_000, "the disturbed attempt stops at once: {stages:?}");
    let taps = at(Stage::Taps);
    assert_eq!(taps.len(), 2, "{stages:?}");
    assert!(taps[1] >= 6_500_000 + RECOVER_US, "the new taps wait for the forces: {stages:?}");
    assert_eq!(at(Stage::Return).len(), 1, "{stages:?}");
    // The log says what disturbed it, when and where.
    assert_eq!(findings.disturbances.len(), 1, "{:?}", findings.disturbances);
    let d = findings.disturbances[0];
    assert!((d.attempt, d.stale, d.stage) == (1, false, Stage::Taps) && (d.gap_ms - 1_501.0).abs() < 10.0, "{d:?}");
    assert!(
        findings.describe().contains("a stall of 1501 ms at 6.5 s (taps, exploration 1)"),
        "{}",
        findings.describe()
    );
}

#[test]
fn a_poke_the_stylus_did_not_follow_reads_as_the_one_before() {
    let (_, r_out, ..) = ring(ArtifactKind::Idol);
    // The stylus stays out through the eighth poke.
    let poke =
        |ex: &Exploration| ex.taps_start_us + (7.0 * TAP_S * 1e6) as u64..ex.taps_start_us + (8.0 * TAP_S * 1e6) as u64;
    let held =
        |ex: &Exploration, t| (ex.stage == Stage::Taps && poke(ex).contains(&t)).then_some(Vec3::new(r_out, 0.0, 0.0));
    let (findings, stages, _) = run_held(|_| Some(1_000), held);
    assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Taps).count(), 1, "{stages:?}");
    assert_eq!((findings.attempts, findings.disturbed), (1, false), "{stages:?}");
    assert_eq!(findings.profile[7], findings.profile[6], "{:?}", findings.profile);
    assert!(findings.profile[7] < r_out - 0.01, "{:?}", findings.profile);
    // A missed poke reads as the one before it, the first as the last.
    let mut ex = Exploration::new(ArtifactKind::Idol, 0, start());
    ex.tap_min.fill(0.02);
    ex.tap_min[7] = r_out;
    ex.tap_min[3] = 0.025;
    assert!(ex.missed().enumerate().all(|(k, missed)| missed == (k == 7)));
    let profile = ex.profile();
    assert_eq!((profile[3], profile[7], profile[8]), (0.025, 0.02, 0.02));
    ex.tap_min[0] = r_out;
    assert_eq!(ex.profile()[0], 0.02, "the first poke reads as the last one");
    let reach = 0.5 * artifact::look(ArtifactKind::Idol).size_m[0] + 0.5 * TOOL_DIAMETER_M + 0.002;
    ex.tap_touch[5] = Some(reach + 0.001);
    ex.tap_touch[6] = Some(reach - 0.001);
    let missed: Vec<usize> = ex.missed().enumerate().filter_map(|(k, m)| m.then_some(k)).collect();
    assert_eq!(missed, [0, 5, 7], "a touch where no copy reaches is missed too");
    assert_eq!((ex.touches()[5], ex.touches()[6]), (None, Some(reach - 0.001)), "never rested on");
    assert!(r_out - 0.005 > reach + 0.001, "closer than where the poke starts");
}

#[test]
fn stale_contact_data_all_along_ends_after_the_last_attempt_marked_disturbed() {
    let (findings, stages) = run(|_| Some(STALE_US + 1));
    assert_eq!((findings.attempts, findings.disturbed), (ATTEMPTS, true), "{stages:?}");
    assert!(findings.describe().contains("disturbed in all 3 explorations"), "{}", findings.describe());
}

#[test]
fn touches_where_nothing_is_on_an_idol_are_missed_and_the_press_goes_to_its_body() {
    // Profiles (mm) of the real idol of seed 10's heist, felt with 48 pokes by the feel_copies
    // example, which read 3, 3, 1 and 3 notches of its 4: touches where nothing is (40.3 mm, 44.4 mm),
    // and a narrow notch read shallow (pokes 42–44; 30–32 in the last: hence 96 pokes for an idol).
    let felt = [
        "36.8 37.0 36.2 36.6 37.1 36.2 31.9 29.0 33.2 35.6 35.4 35.4 35.4 35.8 35.8 36.1 35.5 36.4 33.8 29.4 30.5 36.6 \
         37.0 35.6 37.0 36.8 36.8 37.2 37.2 35.8 33.4 28.8 34.0 36.0 36.2 35.9 36.2 36.2 36.6 36.8 36.5 36.1 34.4 34.4 \
         32.2 37.0 37.1 37.1",
        "36.6 36.8 35.8 36.6 36.5 36.1 31.3 29.0 33.2 35.6 35.1 35.2 35.6 35.6 35.8 36.1 35.3 36.2 33.6 29.3 30.4 36.6 \
         37.1 35.7 36.9 36.7 36.7 36.7 36.9 36.4 33.4 28.8 34.0 36.2 35.9 35.8 36.3 36.4 40.3 36.8 36.5 36.0 34.4 29.7 \
         32.3 37.0 37.2 37.0",
        "36.5 37.1 36.6 36.6 37.1 36.1 31.9 29.0 33.2 35.6 35.4 35.6 35.6 35.8 35.8 36.1 35.6 36.4 33.8 29.4 30.6 36.7 \
         37.3 35.7 37.1 36.8 36.8 37.1 37.1 36.3 33.5 28.9 34.1 36.1 44.4 35.9 36.3 36.3 36.5 36.9 36.5 36.2 34.4 29.6 \
         32.3 36.9 37.2 37.0",
        "36.6 37.4 36.2 36.6 37.0 36.2 31.9 29.0 32.8 35.6 35.4 35.7 35.4 34.9 35.6 36.2 35.4 36.3 33.1 29.4 30.5 36.2 \
         37.4 35.6 37.2 36.8 36.8 37.2 37.1 36.4 33.5 33.5 34.2 36.2 36.4 35.9 36.4 36.4 36.8 36.6 36.2 36.3 34.3 29.7 \
         32.2 37.0 37.1 37.1",
    ];
    for (i, profile) in felt.iter().enumerate() {
        let mut ex = Exploration::new(ArtifactKind::Idol, 0, start());
        let mm: Vec<f32> = profile.split_whitespace().map(|v| v.parse::<f32>().unwrap() * 1e-3).collect();
        assert_eq!(mm.len(), 48);
        (ex.tap_touch, ex.tap_min) = (vec![None; 48], vec![f32::INFINITY; 48]);
        for (touch, r) in ex.tap_touch.iter_mut().zip(mm) {
            *touch = Some(r);
        }
        let spikes: Vec<usize> = ex.missed().enumerate().filter_map(|(k, m)| m.then_some(k)).collect();
        assert_eq!(spikes, [vec![], vec![38], vec![34], vec![]][i], "profile {i}");
        // The press goes to the body, between notches.
        let k = (ex.plain_angle() / TAU * 48.0).round() as usize % 48;
        assert!(ex.profile()[k] > 0.035, "profile {i}: poke {k}");
    }
}

#[test]
fn notches_are_counted_from_the_body_and_a_lone_poke_off_it_is_none() {
    // Four V notches read 4–7 pokes deep, one read shallow (its bottom between two pokes), on a body
    // of 36 ± 0.6 mm with one poke 3.6 mm in and one 2 mm out, as felt on seed 10's idol.
    let mut mm: Vec<f32> = (0..IDOL_TAPS).map(|k| if k % 2 == 0 { 36.6 } else { 35.4 }).collect();
    for (start, depths) in [
        (10, &[1.0, 3.0, 5.0, 7.2, 5.0, 3.0, 1.0][..]),
        (34, &[1.5, 4.0, 6.8, 4.0, 1.5][..]),
        (58, &[1.0, 2.0, 2.7, 2.7, 2.0, 1.0][..]),
        (80, &[2.0, 5.0, 7.0, 5.0, 2.0][..]),
    ] {
        for (k, d) in depths.iter().enumerate() {
            mm[start + k] = 36.0 - d;
        }
    }
    mm[25] = 32.4;
    mm[70] = 38.0;
    let profile: Vec<f32> = mm.iter().map(|v| v * 1e-3).collect();
    assert_eq!(count_notches(&profile), 4, "{mm:?}");
    let whole_range = artifact::count_high_runs(&profile.iter().map(|r| -r).collect::<Vec<_>>());
    assert_eq!(whole_range, 3, "35 % of the whole range misses the shallow notch");
    assert_eq!(count_notches(&[0.03; 12]), 0, "a round body has none");
}

#[test]
fn the_plain_part_is_the_middle_of_the_longest_low_stretch() {
    let mut p = vec![1.0; 12];
    p[3] = 0.0;
    p[7] = 0.0;
    p[8] = 0.0;
    p[9] = 0.0;
    assert_eq!(lowest_run_middle(&p), 8);
    let mut wrap = vec![1.0; 12];
    wrap[11] = 0.0;
    wrap[0] = 0.0;
    wrap[1] = 0.0;
    assert_eq!(lowest_run_middle(&wrap), 0);
}

/// A stroke 12 mm down and back up at 1 N against the copy, with friction `mu` and a push along it of
/// `ridge` N repeating every `spacing` m, plus `bump` N of push at the packing's 1.1 mm.
fn strokes(mu: f32, ridge: f32, spacing: f32, bump: f32) -> Vec<StrokeSample> {
    let mut out = Vec::new();
    for (up, from, to) in [(false, 0.0, -SLIDE_M), (true, -SLIDE_M, 0.0)] {
        for i in 0..500 {
            let height: f32 = from + (to - from) * i as f32 / 500.0;
            let friction = if up { -mu } else { mu };
            let along = friction + ridge * (TAU * height / spacing).sin() + bump * (TAU * height / 0.0011 + 0.3).sin();
            out.push(StrokeSample { height, along, normal: 1.0, up });
        }
    }
    out
}

#[test]
fn ridges_are_found_at_their_spacing_whatever_the_friction() {
    for mu in [0.1, 0.6] {
        let (spacing, strength) = strongest_repeat(&strokes(mu, 0.3, 0.003, 0.05)).expect("stroked");
        assert!((spacing - 0.003).abs() < 0.0003 && (strength - 0.3).abs() < 0.05, "mu {mu}: {spacing} m, {strength}");
    }
    let (spacing, _) = strongest_repeat(&strokes(0.3, 0.3, 0.002, 0.0)).expect("finer ribs");
    assert!((spacing - 0.002).abs() < 0.0002, "{spacing}");
    // The stylus lagging the hand half a ridge one way and not the other (a soft, rough copy): the
    // two ways' repeats are out of phase, and each still counts.
    let lagged: Vec<StrokeSample> = strokes(0.6, 0.3, 0.003, 0.0)
        .into_iter()
        .map(|s| if s.up { StrokeSample { along: -0.6 - (s.along + 0.6), ..s } } else { s })
        .collect();
    let (spacing, strength) = strongest_repeat(&lagged).expect("stroked");
    assert!((spacing - 0.003).abs() < 0.0003 && strength > 0.25, "{spacing} m, {strength}");
}

#[test]
fn friction_and_the_packings_bumps_alone_are_no_ridges() {
    let weak = |s: &[StrokeSample]| strongest_repeat(s).is_some_and(|(_, strength)| strength < RIDGES_ABOVE);
    assert!(weak(&strokes(0.6, 0.0, 0.003, 0.05)) && weak(&strokes(0.1, 0.0, 0.003, 0.0)));
    // A stroke that barely touched says nothing.
    assert_eq!(strongest_repeat(&strokes(0.1, 0.3, 0.003, 0.0)[..40]), None);
}
