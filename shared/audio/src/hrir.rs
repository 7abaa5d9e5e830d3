//! The head-related impulse responses the binaural renderer uses, computed from a spherical head.
//!
//! You need this module to build the `hrtf` crate's HRIR sphere without shipping measured data: the
//! public measured sets we looked at either have no licence we could verify for redistribution (the
//! IRCAM LISTEN sphere inside `fyrox-sound`) or need a conversion tool chain (MIT KEMAR). Brown & Duda's
//! structural model ("A structural model for binaural sound synthesis", IEEE TSAP 1998) gives each ear
//! a head-shadow filter and the interaural time difference of a rigid sphere; it is computed here at
//! start-up, so the repository ships code, not data (licence: the project's own). See docs/audio.md.
//!
//! Listener frame: +x right, +y up, −z forward (Bevy's). The ears sit at ±x.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::Vec3;

/// Head radius, m (Brown & Duda's average adult).
pub const HEAD_RADIUS_M: f32 = 0.0875;
/// Speed of sound, m/s.
pub const SPEED_OF_SOUND_M_PER_S: f32 = 343.0;
/// Samples per impulse response. The responses end within 100 samples, but `hrtf` 0.9 resamples every
/// response on loading (even at the same rate) and its resampler delays them by 127 samples without
/// trimming: the rest of the 256 keeps them whole (checked in `the_sphere_loads_in_the_hrtf_crate`).
pub const HRIR_LEN: usize = 256;
/// Delay common to both ears so that every response is causal, s.
const BASE_DELAY_S: f32 = 0.0003;

/// Arrival delay at an ear for a source in unit direction `dir`, relative to the head's centre plus
/// [`BASE_DELAY_S`], s (Woodworth/Brown–Duda: −(a/c)·cos θ in front of the ear, (a/c)(θ − π/2) behind it).
pub fn ear_delay_s(ear: Vec3, dir: Vec3) -> f32 {
    let theta = ear.dot(dir).clamp(-1.0, 1.0).acos();
    let a_c = HEAD_RADIUS_M / SPEED_OF_SOUND_M_PER_S;
    let t = if theta < FRAC_PI_2 { -a_c * theta.cos() } else { a_c * (theta - FRAC_PI_2) };
    BASE_DELAY_S + a_c + t
}

/// The head-shadow zero's coefficient α(θ): 2 (a +6 dB high shelf) facing the ear, 0.1 (a deep
/// shadow) at 150° away from it.
pub fn shadow_alpha(ear: Vec3, dir: Vec3) -> f32 {
    let theta = ear.dot(dir).clamp(-1.0, 1.0).acos();
    1.05 + 0.95 * (theta * 180.0 / 150.0).cos()
}

/// One ear's impulse response at `sample_rate` for a source in unit direction `dir`.
pub fn ear_response(ear: Vec3, dir: Vec3, sample_rate: u32) -> Vec<f32> {
    let fs = sample_rate as f32;
    // Fractional delay as a two-tap split, then the one-pole, one-zero shadow filter (bilinear transform).
    let delay = ear_delay_s(ear, dir) * fs;
    let mut x = vec![0.0f32; HRIR_LEN];
    let i = delay.floor() as usize;
    let frac = delay - delay.floor();
    if i + 1 < HRIR_LEN {
        x[i] = 1.0 - frac;
        x[i + 1] = frac;
    }
    let w0 = SPEED_OF_SOUND_M_PER_S / HEAD_RADIUS_M;
    let alpha = shadow_alpha(ear, dir);
    let k = 2.0 * fs;
    let norm = 2.0 * w0 + k;
    let (b0, b1, a1) = ((2.0 * w0 + alpha * k) / norm, (2.0 * w0 - alpha * k) / norm, (2.0 * w0 - k) / norm);
    let (mut x1, mut y1) = (0.0, 0.0);
    x.iter()
        .map(|&xn| {
            let y = b0 * xn + b1 * x1 - a1 * y1;
            (x1, y1) = (xn, y);
            y
        })
        .collect()
}

/// Unit directions and triangles of a sphere: an icosahedron subdivided `levels` times.
pub fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mids = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize());
                (v.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// The model's HRIR sphere in the `hrtf` crate's binary format ("HRIR", rate, length, counts, faces, points).
pub fn sphere_bytes(sample_rate: u32) -> Vec<u8> {
    let (points, faces) = icosphere(2);
    let mut out = Vec::with_capacity(20 + faces.len() * 12 + points.len() * (12 + 8 * HRIR_LEN));
    out.extend_from_slice(b"HRIR");
    for n in [sample_rate, HRIR_LEN as u32, points.len() as u32, (faces.len() * 3) as u32] {
        out.extend_from_slice(&n.to_le_bytes());
    }
    for i in faces.iter().flatten() {
        out.extend_from_slice(&i.to_le_bytes());
    }
    for p in &points {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for ear in [Vec3::NEG_X, Vec3::X] {
            for s in ear_response(ear, *p, sample_rate) {
                out.extend_from_slice(&s.to_le_bytes());
            }
        }
    }
    out
}

/// Angle of `dir` to the right of straight ahead, rad (for the time/level fallback).
pub fn azimuth(dir: Vec3) -> f32 {
    dir.x.atan2(-dir.z).clamp(-PI, PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn energy(h: &[f32]) -> f32 {
        h.iter().map(|s| s * s).sum()
    }

    fn onset(h: &[f32]) -> usize {
        h.iter().position(|s| s.abs() > 0.05).unwrap_or(usize::MAX)
    }

    #[test]
    fn a_source_on_the_right_reaches_the_right_ear_first_and_louder() {
        let (l, r) = (ear_response(Vec3::NEG_X, Vec3::X, 48_000), ear_response(Vec3::X, Vec3::X, 48_000));
        assert!(energy(&r) > 2.0 * energy(&l), "right {} left {}", energy(&r), energy(&l));
        // ≈ 0.66 ms interaural difference at 90°: about 31 samples at 48 kHz.
        let itd = onset(&l) as i64 - onset(&r) as i64;
        assert!((25..=37).contains(&itd), "itd {itd} samples");
    }

    #[test]
    fn a_source_straight_ahead_is_the_same_in_both_ears() {
        let (l, r) = (ear_response(Vec3::NEG_X, Vec3::NEG_Z, 48_000), ear_response(Vec3::X, Vec3::NEG_Z, 48_000));
        for (a, b) in l.iter().zip(&r) {
            assert!((a - b).abs() < 1e-6);
        }
    }

    #[test]
    fn the_sphere_loads_in_the_hrtf_crate() {
        let sphere = hrtf::HrirSphere::new(std::io::Cursor::new(sphere_bytes(48_000)), 48_000).expect("loads");
        assert_eq!(sphere.points().len(), 162);
        let right = sphere.points().iter().find(|p| p.pos.x > 0.99).expect("a point on the right");
        let e = |h: &[f32]| h.iter().map(|s| s * s).sum::<f32>();
        let original = ear_response(Vec3::X, Vec3::X, 48_000);
        assert!((e(right.right_hrir()) / e(&original) - 1.0).abs() < 0.05, "the response survives loading whole");
    }
}
