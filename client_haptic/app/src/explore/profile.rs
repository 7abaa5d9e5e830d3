//! What the touch bot makes of what it felt: a stroke's repeating push (ridges), a circular profile's
//! notches and lowest run, medians. Pure functions over the samples.

use std::f32::consts::TAU;

use heist_shared::artifact;

/// Contact force that counts as touching, N.
pub(super) const TOUCH_N: f32 = 0.05;
/// Length of the strokes down and up, m.
pub(super) const SLIDE_M: f32 = 0.012;
/// One in-touch sample of a stroke: the stylus's height, the contact force along the stroke and into
/// the copy, and which way it went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct StrokeSample {
    pub(super) height: f32,
    pub(super) along: f32,
    pub(super) normal: f32,
    pub(super) up: bool,
}

/// Shortest and longest ridge spacing looked for, m: the stroke must cross at least three.
const RIDGE_SPACINGS_M: (f32, f32) = (0.0015, SLIDE_M / 3.0);
/// A push along the stroke that repeats with the stylus's height, this strong against the normal force
/// (its Fourier amplitude over each way of the stroke), means ridges. Ribbed copies gave 0.25–0.48 and
/// the packing's bumps on smooth ones at most 0.12 through the proxy, 0.24 once through the volumetric
/// rendering (seeds 21–24, docs/phantom-client.md) before the copy had a surface grid, at most 0.02 since
/// (seeds 3, 5, 11).
pub const RIDGES_ABOVE: f32 = 0.18;

/// The spacing at which the push along the stroke (less its mean on each way: the friction) repeats
/// most strongly with the stylus's height on each way, and that strength over the mean normal force;
/// None for fewer than 64 samples in touch.
pub(super) fn strongest_repeat(strokes: &[StrokeSample]) -> Option<(f32, f32)> {
    if strokes.len() < 64 {
        return None;
    }
    let mean = |up: bool| {
        let (sum, n) = strokes.iter().filter(|s| s.up == up).fold((0.0, 0u32), |(a, n), s| (a + s.along, n + 1));
        if n > 0 { sum / n as f32 } else { 0.0 }
    };
    let (mean_up, mean_down) = (mean(true), mean(false));
    let normal = strokes.iter().map(|s| s.normal).sum::<f32>() / strokes.len() as f32;
    // Each way on its own: the stylus lags the hand by up to the friction cone, one way down and the
    // other way up, so the two ways' repeats can be out of phase (by half a ridge on a soft rough copy).
    let strength = |spacing: f32| {
        let (mut amplitude, mut total) = (0.0f32, 0.0f32);
        for up in [false, true] {
            let (mut c, mut s, mut travel) = (0.0f32, 0.0f32, 0.0f32);
            for w in strokes.windows(2).filter(|w| w[0].up == up && w[1].up == up) {
                let (a, b) = (w[0], w[1]);
                let dy = (b.height - a.height).abs();
                if dy > 0.001 {
                    continue; // a gap in touch
                }
                let push = b.along - if up { mean_up } else { mean_down };
                let phase = TAU * b.height / spacing;
                c += push * phase.cos() * dy;
                s += push * phase.sin() * dy;
                travel += dy;
            }
            if travel > 0.0 {
                amplitude += 2.0 * c.hypot(s);
                total += travel;
            }
        }
        if total > 0.0 { amplitude / total / normal.max(TOUCH_N) } else { 0.0 }
    };
    let (lo, hi) = RIDGE_SPACINGS_M;
    (0..=64)
        .map(|i| lo * (hi / lo).powf(i as f32 / 64.0))
        .map(|spacing| (spacing, strength(spacing)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The median of `v` (the upper one of an even count), if any.
pub(super) fn median(mut v: Vec<f32>) -> Option<f32> {
    v.sort_by(f32::total_cmp);
    v.get(v.len() / 2).copied()
}

/// Notches in an idol's circular profile of [`IDOL_TAPS`](super::IDOL_TAPS) pokes, measured from its body (the median:
/// notches are under half the circle) rather than from its widest touch. A notch spans four pokes or
/// more; a single poke that touched too early or too late (seen 3.6 mm below the body and 2 mm above,
/// between pokes that read the body) is no notch, so each poke reads as the median of itself and its two
/// neighbours. A notch starts 30 % of the way from the body down to the deepest poke and ends 15 % of the
/// way (hysteresis); a profile varying less than [`artifact::MIN_FEATURE_SIZE_M`] has none.
pub(super) fn count_notches(profile: &[f32]) -> u32 {
    let n = profile.len();
    let profile: Vec<f32> = (0..n)
        .map(|i| median(vec![profile[(i + n - 1) % n], profile[i], profile[(i + 1) % n]]).unwrap_or(0.0))
        .collect();
    let (Some(body), Some(start)) =
        (median(profile.clone()), profile.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i))
    else {
        return 0;
    };
    let deepest = profile.iter().copied().fold(f32::INFINITY, f32::min);
    if body - deepest < artifact::MIN_FEATURE_SIZE_M {
        return 0;
    }
    let (enter, leave) = (body - 0.3 * (body - deepest), body - 0.15 * (body - deepest));
    let (mut inside, mut notches) = (false, 0);
    // Starting at the widest poke, the circle begins and ends outside a notch: none is cut in two.
    for i in 0..n {
        let r = profile[(start + i) % n];
        if !inside && r < enter {
            (inside, notches) = (true, notches + 1);
        } else if inside && r > leave {
            inside = false;
        }
    }
    notches
}

/// Index at the middle of the longest stretch within 25 % of the profile's minimum.
pub(super) fn lowest_run_middle(profile: &[f32]) -> usize {
    let n = profile.len();
    let (min, max) = profile.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let low = |i: usize| profile[i % n] <= min + 0.25 * (max - min);
    let mut best = (0, 0);
    for start in 0..n {
        if low(start) && !low(start + n - 1) {
            let len = (0..n).take_while(|&j| low(start + j)).count();
            if len > best.1 {
                best = (start, len);
            }
        }
    }
    if best.1 == 0 { 0 } else { (best.0 + best.1 / 2) % n }
}
