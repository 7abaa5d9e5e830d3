//! A small isolated-word recognizer for the tests: it hears which words of a closed vocabulary a
//! recording says, in order. Words are cut where the speech pauses (energy below the recording's loudest
//! by 35 dB for 150 ms or more: the stop inside "victor" is silent for 70 ms, the pause after a comma
//! at 120 words a minute is 270 ms or more); each cut is compared with every word of the vocabulary as
//! espeak-ng says it (the same voice and rate the client speaks with) by dynamic time warping over
//! log-mel spectra with the mean removed (so the binaural placement's colouring and the level do not
//! matter); a cut whose best match is not clearly better than the second best (below 0.6 of its
//! distance), or not close at all (a distance of 7 or more), is no word. Measured on espeak-ng's own
//! sentences: a word of the vocabulary scores 1.3–4.9 against its template and 9 or more against every
//! other.
//!
//! You need this module to check what the client *said* from its audio alone (`--wav`), not from what it
//! printed.
#![allow(dead_code)]

use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

/// The rate everything is heard at.
pub const RATE: usize = 48_000;
const FRAME: usize = 1200; // 25 ms
const HOP: usize = 480; // 10 ms
const FFT: usize = 2048;
const BANDS: usize = 24;
/// Quiet hops that end an utterance (150 ms).
const PAUSE_HOPS: usize = 15;

/// Log-mel spectra of a mono signal at [`RATE`], one row per 10 ms.
pub struct Features {
    fft: Arc<dyn Fft<f32>>,
    filters: Vec<Vec<(usize, f32)>>,
    window: Vec<f32>,
}

impl Default for Features {
    fn default() -> Self {
        let mel = |f: f32| 2595.0 * (1.0 + f / 700.0).log10();
        let hz = |m: f32| 700.0 * (10f32.powf(m / 2595.0) - 1.0);
        let (lo, hi) = (mel(100.0), mel(7000.0));
        let edges: Vec<f32> = (0..BANDS + 2).map(|i| hz(lo + (hi - lo) * i as f32 / (BANDS + 1) as f32)).collect();
        let bin = |f: f32| f * FFT as f32 / RATE as f32;
        let filters = (0..BANDS)
            .map(|b| {
                let (l, c, r) = (bin(edges[b]), bin(edges[b + 1]), bin(edges[b + 2]));
                (l.floor() as usize..=r.ceil() as usize)
                    .filter_map(|k| {
                        let x = k as f32;
                        let w = if x < c { (x - l) / (c - l) } else { (r - x) / (r - c) };
                        (w > 0.0).then_some((k, w))
                    })
                    .collect()
            })
            .collect();
        let window =
            (0..FRAME).map(|i| 0.5 - 0.5 * (std::f32::consts::TAU * i as f32 / (FRAME - 1) as f32).cos()).collect();
        Self { fft: FftPlanner::new().plan_fft_forward(FFT), filters, window }
    }
}

impl Features {
    /// Log-mel rows of `x`, each row's mean over time removed.
    pub fn of(&self, x: &[f32]) -> Vec<[f32; BANDS]> {
        let mut rows = Vec::new();
        let mut buf = vec![Complex::new(0.0f32, 0.0); FFT];
        let mut at = 0;
        while at + FRAME <= x.len() {
            buf.iter_mut().for_each(|c| *c = Complex::new(0.0, 0.0));
            for i in 0..FRAME {
                buf[i].re = x[at + i] * self.window[i];
            }
            self.fft.process(&mut buf);
            let mut row = [0.0f32; BANDS];
            for (b, f) in self.filters.iter().enumerate() {
                let e: f32 = f.iter().map(|(k, w)| buf[*k].norm_sqr() * w).sum();
                row[b] = (e + 1e-9).ln();
            }
            rows.push(row);
            at += HOP;
        }
        if !rows.is_empty() {
            let mut mean = [0.0f32; BANDS];
            for r in &rows {
                for b in 0..BANDS {
                    mean[b] += r[b] / rows.len() as f32;
                }
            }
            for r in &mut rows {
                for b in 0..BANDS {
                    r[b] -= mean[b];
                }
            }
        }
        rows
    }
}

/// Dynamic time warping distance between two feature sequences, per step of the path.
pub fn dtw(a: &[[f32; BANDS]], b: &[[f32; BANDS]]) -> f32 {
    if a.is_empty() || b.is_empty() {
        return f32::INFINITY;
    }
    let d = |i: usize, j: usize| a[i].iter().zip(&b[j]).map(|(x, y)| (x - y).powi(2)).sum::<f32>().sqrt();
    let (n, m) = (a.len(), b.len());
    let mut cost = vec![f32::INFINITY; (n + 1) * (m + 1)];
    let mut steps = vec![0u32; (n + 1) * (m + 1)];
    cost[0] = 0.0;
    let at = |i: usize, j: usize| i * (m + 1) + j;
    for i in 1..=n {
        for j in 1..=m {
            let (c, s) = [(at(i - 1, j - 1)), (at(i - 1, j)), (at(i, j - 1))]
                .into_iter()
                .map(|k| (cost[k], steps[k]))
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .unwrap_or((f32::INFINITY, 0));
            cost[at(i, j)] = c + d(i - 1, j - 1);
            steps[at(i, j)] = s + 1;
        }
    }
    cost[at(n, m)] / steps[at(n, m)].max(1) as f32
}

/// The stretches of `x` where something is said: (start, end) in samples.
pub fn utterances(x: &[f32]) -> Vec<(usize, usize)> {
    let energy: Vec<f32> =
        x.chunks(HOP).map(|c| 10.0 * (c.iter().map(|s| s * s).sum::<f32>() / c.len() as f32 + 1e-12).log10()).collect();
    let loudest = energy.iter().copied().fold(f32::MIN, f32::max);
    let loud: Vec<bool> = energy.iter().map(|e| *e > loudest - 35.0).collect();
    let mut out = Vec::new();
    let mut start = None;
    let mut quiet = 0;
    for (i, l) in loud.iter().enumerate() {
        match (*l, start) {
            (true, None) => {
                start = Some(i);
                quiet = 0;
            }
            (true, Some(_)) => quiet = 0,
            (false, Some(s)) => {
                quiet += 1;
                if quiet >= PAUSE_HOPS {
                    out.push((s * HOP, (i + 1 - quiet) * HOP));
                    start = None;
                }
            }
            (false, None) => {}
        }
    }
    if let Some(s) = start {
        out.push((s * HOP, (loud.len() - quiet) * HOP));
    }
    out.into_iter().map(|(s, e)| (s, e.min(x.len()))).filter(|(s, e)| e.saturating_sub(*s) >= 5 * HOP).collect()
}

/// A closed vocabulary, each word as espeak-ng says it.
pub struct Vocabulary {
    features: Features,
    words: Vec<(String, Vec<[f32; BANDS]>)>,
}

/// espeak-ng's speech of `text` at `wpm`, at [`RATE`].
pub fn espeak(text: &str, wpm: u32) -> Vec<f32> {
    let path = std::env::temp_dir().join(format!("listen-{}-{}-{wpm}.wav", std::process::id(), rand_name(text)));
    let status = std::process::Command::new("espeak-ng")
        .args(["-s", &wpm.to_string(), "-w"])
        .arg(&path)
        .arg("--")
        .arg(text)
        .status()
        .expect("espeak-ng runs (scripts/deps.sh installs it)");
    assert!(status.success(), "espeak-ng said {text:?}");
    let samples = heist_voice::mic::read_wav(&path).expect("espeak-ng's file reads");
    let _ = std::fs::remove_file(path);
    samples
}

fn rand_name(text: &str) -> String {
    text.bytes().filter(u8::is_ascii_alphanumeric).take(16).map(char::from).collect()
}

impl Vocabulary {
    /// The words, said at `wpm`.
    pub fn new(words: &[&str], wpm: u32) -> Self {
        let features = Features::default();
        let words = words
            .iter()
            .map(|w| {
                let said = espeak(w, wpm);
                let (s, e) = utterances(&said).into_iter().fold((usize::MAX, 0), |(a, b), (s, e)| (a.min(s), b.max(e)));
                (w.to_string(), features.of(&said[s.min(said.len())..e.max(s).min(said.len())]))
            })
            .collect();
        Self { features, words }
    }

    /// The best two words for `x` with their distances.
    pub fn scores(&self, x: &[f32]) -> [(f32, &str); 2] {
        let f = self.features.of(x);
        let mut scored: Vec<(f32, &str)> = self.words.iter().map(|(w, t)| (dtw(&f, t), w.as_str())).collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        [scored[0], scored[1]]
    }

    /// The word said in `x` (one utterance), if one clearly is.
    pub fn recognize(&self, x: &[f32]) -> Option<&str> {
        let [best, second] = self.scores(x);
        (best.0 < 7.0 && best.0 < 0.6 * second.0).then_some(best.1)
    }

    /// Every utterance of `x`, recognized (None: not a word of the vocabulary).
    pub fn transcribe(&self, x: &[f32]) -> Vec<Option<String>> {
        utterances(x).into_iter().map(|(s, e)| self.recognize(&x[s..e]).map(str::to_owned)).collect()
    }
}
