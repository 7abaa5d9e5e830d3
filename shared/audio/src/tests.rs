//! Offline listening tests: the engine renders into memory and the frames are measured.

use super::*;

fn engine(spatial: SpatialMode) -> AudioEngine {
    AudioEngine::new(&AudioSettings { output: AudioOutput::Manual, spatial, ..Default::default() })
        .expect("engine starts")
}

/// A 20 ms noise burst.
fn click() -> StaticSoundData {
    let mut n = synth::Noise::new(5);
    let s: Vec<f32> = (0..960).map(|_| 0.5 * n.next_sample()).collect();
    synth::mono(&s)
}

fn energy(frames: &[(f32, f32)]) -> (f32, f32) {
    frames.iter().fold((0.0, 0.0), |(l, r), f| (l + f.0 * f.0, r + f.1 * f.1))
}

/// How many samples the left ear lags the right (the lag of the cross-correlation's peak).
fn left_lag(frames: &[(f32, f32)]) -> i64 {
    (-60i64..=60)
        .map(|lag| {
            let c: f32 = (60..frames.len() - 60).map(|i| frames[i].1 * frames[(i as i64 + lag) as usize].0).sum();
            (lag, c)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(lag, _)| lag)
}

fn right_source_is_louder_and_earlier_in_the_right_ear(spatial: SpatialMode) {
    let mut e = engine(spatial);
    e.play_at(click(), Vec3::new(2.0, 0.0, 0.0), "click");
    let frames = e.capture().expect("memory output").render(9600);
    let (l, r) = energy(&frames);
    assert!(r > 2.0 * l, "{spatial:?}: right {r} left {l}");
    // The left ear hears it later: about 0.66 ms at 90°, 32 samples at 48 kHz.
    let lag = left_lag(&frames);
    assert!((20..=45).contains(&lag), "{spatial:?}: the left ear lags by {lag} samples");
}

#[test]
fn a_source_on_the_right_is_louder_in_the_right_ear_and_arrives_there_first_through_the_hrtf() {
    right_source_is_louder_and_earlier_in_the_right_ear(SpatialMode::Hrtf);
}

#[test]
fn the_time_and_level_fallback_also_puts_a_right_source_on_the_right() {
    right_source_is_louder_and_earlier_in_the_right_ear(SpatialMode::TimeLevel);
}

#[test]
fn a_source_on_the_left_is_louder_in_the_left_ear() {
    let mut e = engine(SpatialMode::Hrtf);
    e.play_at(click(), Vec3::new(-2.0, 0.0, -0.5), "click");
    let (l, r) = energy(&e.capture().expect("memory output").render(9600));
    assert!(l > 2.0 * r, "left {l} right {r}");
}

#[test]
fn a_source_four_times_farther_is_four_times_quieter() {
    let rms = |distance: f32| {
        let mut e = engine(SpatialMode::Hrtf);
        e.play_at(click(), Vec3::new(0.0, 0.0, -distance), "click");
        let (l, r) = energy(&e.capture().expect("memory output").render(9600));
        ((l + r) / 2.0).sqrt()
    };
    let (near, far) = (rms(2.0), rms(8.0));
    assert!(near > 0.0);
    let ratio = near / far;
    assert!((3.5..4.5).contains(&ratio), "amplitude ratio {ratio} for 2 m vs 8 m");
    assert_eq!(rms(binaural::MAX_DISTANCE_M + 1.0), 0.0, "past the maximum distance a source is silent");
}

#[test]
fn a_contact_makes_a_contact_sound_and_free_space_is_silent() {
    let mut e = engine(SpatialMode::Hrtf);
    let capture = e.capture().expect("memory output").clone();
    e.contact(ContactParams::default());
    let (l, r) = energy(&capture.render(24_000));
    assert!(l + r < 1e-9, "free space: energy {}", l + r);
    e.contact(ContactParams { force_n: 1.5, slip_m_per_s: 0.05, hardness: 1.0, roughness: 1.0, ridges_per_s: 0.0 });
    let (l, r) = energy(&capture.render(24_000));
    assert!(l + r > 1e-2, "sliding contact: energy {}", l + r);
    e.contact(ContactParams::default());
    capture.render(24_000);
    let (l, r) = energy(&capture.render(24_000));
    assert!(l + r < 1e-6, "after lifting the stylus: energy {}", l + r);
    e.tap(1.0);
    let (l, r) = energy(&capture.render(4_800));
    assert!(l + r > 1e-3, "a tap: energy {}", l + r);
}

#[test]
fn a_rough_scrape_is_louder_than_a_smooth_one() {
    let scrape = |roughness: f32| {
        let mut e = engine(SpatialMode::TimeLevel);
        let capture = e.capture().expect("memory output").clone();
        e.contact(ContactParams { force_n: 1.0, slip_m_per_s: 0.05, hardness: 0.5, roughness, ..Default::default() });
        capture.render(4_800);
        let (l, r) = energy(&capture.render(24_000));
        l + r
    };
    assert!(scrape(1.0) > 1.5 * scrape(0.0));
}

/// Strength of the loudness swing that repeats `per_s` times a second in `frames` (48 kHz), relative
/// to the mean loudness (a Fourier coefficient of the 2 ms energy envelope).
fn swing_at(frames: &[(f32, f32)], per_s: f32) -> f32 {
    let envelope: Vec<f32> = frames.chunks(96).map(|c| c.iter().map(|f| f.0 * f.0 + f.1 * f.1).sum()).collect();
    let mean = envelope.iter().sum::<f32>() / envelope.len() as f32;
    let (mut c, mut s) = (0.0f32, 0.0f32);
    for (i, e) in envelope.iter().enumerate() {
        let phase = std::f32::consts::TAU * per_s * i as f32 * 0.002;
        c += (e - mean) * phase.cos();
        s += (e - mean) * phase.sin();
    }
    2.0 * c.hypot(s) / envelope.len() as f32 / mean.max(f32::MIN_POSITIVE)
}

#[test]
fn a_scrape_over_ridges_swells_once_per_ridge_and_a_smooth_one_does_not() {
    let scrape = |ridges_per_s: f32| {
        let mut e = engine(SpatialMode::TimeLevel);
        let capture = e.capture().expect("memory output").clone();
        e.contact(ContactParams { force_n: 1.0, slip_m_per_s: 0.05, hardness: 0.5, roughness: 1.0, ridges_per_s });
        capture.render(9_600);
        capture.render(48_000)
    };
    let ribbed = scrape(17.0);
    let smooth = scrape(0.0);
    let (at, off) = (swing_at(&ribbed, 17.0), swing_at(&ribbed, 11.0));
    let plain = swing_at(&smooth, 17.0);
    assert!(at > 0.5, "the scrape swells 17 times a second over 17 ridges a second: {at}");
    assert!(at > 4.0 * off, "at the ridges' rate, not another: {at} vs {off} at 11/s");
    assert!(plain < 0.2 * at, "a smooth scrape has no such swing: {plain}");
}

#[test]
fn hrtf_turned_off_while_playing_renders_as_time_and_level_from_then_on() {
    let mut switched = engine(SpatialMode::Hrtf);
    assert!(switched.uses_hrtf());
    switched.set_hrtf(false);
    assert!(!switched.uses_hrtf());
    let mut plain = engine(SpatialMode::TimeLevel);
    for e in [&mut switched, &mut plain] {
        e.play_at(click(), Vec3::new(2.0, 0.0, 0.0), "click");
    }
    let a = switched.capture().expect("memory output").render(4800);
    let b = plain.capture().expect("memory output").render(4800);
    let diff: f32 = a.iter().zip(&b).map(|(x, y)| (x.0 - y.0).abs() + (x.1 - y.1).abs()).sum();
    assert!(diff < 1e-3, "the same as an engine started without HRTF: {diff}");
    switched.set_hrtf(true);
    switched.play_at(click(), Vec3::new(2.0, 0.0, 0.0), "click");
    let c = switched.capture().expect("memory output").render(4800);
    plain.play_at(click(), Vec3::new(2.0, 0.0, 0.0), "click");
    let d = plain.capture().expect("memory output").render(4800);
    let diff: f32 = c.iter().zip(&d).map(|(x, y)| (x.0 - y.0).abs() + (x.1 - y.1).abs()).sum();
    assert!(diff > 1.0, "turned back on, it renders through the HRTF again: {diff}");
}

#[test]
fn speech_lines_are_said_one_after_the_other_never_over_each_other() {
    let mut e = engine(SpatialMode::Hrtf);
    let capture = e.capture().expect("memory output").clone();
    // Two half-second "lines" given at once: the second starts when the first has ended.
    let line = synth::mono(&vec![0.5; 24_000]);
    e.speak(line.clone());
    e.speak(line);
    assert!(e.is_speaking());
    let mut loud = 0;
    for _ in 0..30 {
        let frames = capture.render(4800);
        loud += frames.iter().filter(|f| f.0.abs() + f.1.abs() > 0.05).count();
        e.update();
    }
    // Overlapping, they would have sounded for half a second; in turn, for about a second.
    assert!(loud > 40_000, "{loud} loud frames");
    assert!(!e.is_speaking());
}

#[test]
fn each_groups_volume_sets_its_own_level() {
    let mut e = engine(SpatialMode::TimeLevel);
    let capture = e.capture().expect("memory output").clone();
    e.set_volumes(Volumes { earcon_db: kira::Decibels::SILENCE.0, ..Default::default() });
    capture.render(4800);
    e.earcon(synth::Earcon::Won);
    let (l, r) = energy(&capture.render(48_000));
    assert!(l + r < 1e-6, "earcons muted: {}", l + r);
    e.play_at(click(), Vec3::new(0.0, 0.0, -1.0), "click");
    let (l, r) = energy(&capture.render(9600));
    assert!(l + r > 1.0, "the museum still plays: {}", l + r);
}
