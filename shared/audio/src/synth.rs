//! Every sound the client makes, synthesized (no sample files): the museum's noises, earcons, and the
//! contact sound of the stylus on a copy.
//!
//! You need this module to change how something sounds. One-shots are [`StaticSoundData`] built once
//! at start-up; the contact sound is a kira [`Sound`] that runs forever and follows the haptic contact
//! (force, sliding speed, material) through a triple buffer, so the audio thread never waits.

use std::f32::consts::TAU;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use kira::Frame;
use kira::info::Info;
use kira::sound::static_sound::{StaticSoundData, StaticSoundSettings};
use kira::sound::{Sound, SoundData};

/// Sample rate of the synthesized sounds, Hz.
pub const RATE: u32 = 48_000;

/// A mono signal as kira sound data.
pub fn mono(samples: &[f32]) -> StaticSoundData {
    let frames: Arc<[Frame]> = samples.iter().map(|&s| Frame { left: s, right: s }).collect();
    StaticSoundData { sample_rate: RATE, frames, settings: StaticSoundSettings::default(), slice: None }
}

/// xorshift32 noise in −1..1: deterministic and allocation-free.
#[derive(Clone, Copy, Debug)]
pub struct Noise(u32);

impl Noise {
    /// Noise from a non-zero seed.
    pub fn new(seed: u32) -> Self {
        Self(seed.max(1))
    }

    /// The next sample.
    pub fn next_sample(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0 as f32 / u32::MAX as f32 * 2.0 - 1.0
    }
}

fn samples(seconds: f32, mut f: impl FnMut(f32) -> f32) -> Vec<f32> {
    (0..(seconds * RATE as f32) as usize).map(|i| f(i as f32 / RATE as f32)).collect()
}

/// A footstep: a short low-passed noise burst.
pub fn footstep(seed: u32) -> StaticSoundData {
    let mut noise = Noise::new(seed);
    let mut lp = 0.0;
    mono(&samples(0.09, |t| {
        lp += 0.15 * (noise.next_sample() - lp);
        lp * 0.9 * (-t / 0.02).exp()
    }))
}

/// Breaking glass: a crack, then bright tinkles.
pub fn glass() -> StaticSoundData {
    let mut noise = Noise::new(7);
    let partials = [2900.0, 3700.0, 4410.0, 5230.0, 6170.0, 7040.0];
    mono(&samples(0.9, |t| {
        let crack = noise.next_sample() * (-t / 0.03).exp();
        let tinkle: f32 = partials
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let onset = 0.02 + 0.07 * i as f32;
                if t < onset { 0.0 } else { (TAU * f * t).sin() * (-(t - onset) / 0.12).exp() * 0.07 }
            })
            .sum();
        0.5 * crack + tinkle
    }))
}

/// A thrown object landing: a low knock.
pub fn thud() -> StaticSoundData {
    let mut noise = Noise::new(11);
    mono(&samples(0.35, |t| ((TAU * 85.0 * t).sin() * 0.8 + noise.next_sample() * 0.15) * (-t / 0.07).exp()))
}

/// One second of the alarm's two-tone siren.
pub fn alarm() -> StaticSoundData {
    mono(&samples(1.0, |t| {
        let f = if t < 0.5 { 950.0 } else { 760.0 };
        0.35 * (TAU * f * t).sin().signum() * 0.5 + 0.2 * (TAU * f * t).sin()
    }))
}

/// The earcons: short pitched cues that mean the same thing every time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Earcon {
    /// A copy arrived on the workbench (one soft blip).
    CopyArrived,
    /// The copy can be felt (two quick blips).
    ReadyToFeel,
    /// A verdict was right (rising fifth).
    Right,
    /// A verdict was wrong (falling minor second).
    Wrong,
    /// The alarm went up (three fast high beeps).
    AlarmUp,
    /// The heist is won (rising arpeggio).
    Won,
    /// The heist is lost (falling arpeggio).
    Lost,
    /// The partner joined or came back (two rising notes, a third apart).
    PartnerIn,
    /// The partner left or dropped (two falling notes, a third apart).
    PartnerOut,
    /// The connection to the server is lost (two low notes).
    LinkDown,
    /// The connection is back (two quick low-to-high notes).
    LinkUp,
    /// The partner's client has the warning (a short high chirp).
    WarningHeard,
    /// A walkie-talkie transmission starts (a squelch burst and a click).
    SquelchOpen,
    /// A walkie-talkie transmission ends (a squelch tail and a low beep).
    SquelchClose,
}

/// The earcon's sound.
pub fn earcon(e: Earcon) -> StaticSoundData {
    match e {
        Earcon::SquelchOpen => return squelch(0.08, 1800.0),
        Earcon::SquelchClose => return squelch(0.16, 900.0),
        _ => {}
    }
    let notes: &[(f32, f32)] = match e {
        Earcon::CopyArrived => &[(660.0, 0.12)],
        Earcon::ReadyToFeel => &[(880.0, 0.07), (880.0, 0.07)],
        Earcon::Right => &[(523.0, 0.12), (784.0, 0.2)],
        Earcon::Wrong => &[(415.0, 0.15), (392.0, 0.3)],
        Earcon::AlarmUp => &[(1400.0, 0.06), (1400.0, 0.06), (1400.0, 0.06)],
        Earcon::Won => &[(523.0, 0.12), (659.0, 0.12), (784.0, 0.12), (1047.0, 0.3)],
        Earcon::Lost => &[(784.0, 0.15), (622.0, 0.15), (523.0, 0.15), (392.0, 0.4)],
        Earcon::PartnerIn => &[(587.0, 0.1), (740.0, 0.16)],
        Earcon::PartnerOut => &[(740.0, 0.1), (587.0, 0.16)],
        Earcon::LinkDown => &[(262.0, 0.15), (262.0, 0.25)],
        Earcon::LinkUp => &[(262.0, 0.08), (392.0, 0.12)],
        Earcon::WarningHeard => &[(1760.0, 0.05)],
        Earcon::SquelchOpen | Earcon::SquelchClose => &[],
    };
    let mut out = Vec::new();
    for &(f, d) in notes {
        out.extend(samples(d, |t| 0.3 * (TAU * f * t).sin() * (t / 0.005).min(1.0) * (-(t / d) * 3.0).exp()));
        out.extend(samples(0.03, |_| 0.0));
    }
    mono(&out)
}

/// A radio's squelch: band-passed noise for `len` seconds ending in a short beep at `beep_hz`.
fn squelch(len: f32, beep_hz: f32) -> StaticSoundData {
    let mut noise = Noise::new(23);
    let (mut lp, mut hp) = (0.0, 0.0);
    let mut out = samples(len, |t| {
        // A crude band-pass (about 300 Hz to 3 kHz), the band a walkie-talkie carries.
        let n = noise.next_sample();
        lp += 0.3 * (n - lp);
        hp += 0.04 * (lp - hp);
        0.35 * (lp - hp) * (t / 0.003).min(1.0) * (1.0 - t / len).max(0.0).sqrt()
    });
    out.extend(samples(0.04, |t| 0.2 * (TAU * beep_hz * t).sin() * (1.0 - t / 0.04)));
    mono(&out)
}

/// A guard's radio: a squelch, a burst of garbled band-limited voice, a squelch tail.
pub fn radio_squawk() -> StaticSoundData {
    let mut noise = Noise::new(31);
    let (mut lp, mut hp) = (0.0, 0.0);
    let len = 0.7;
    let mut phase = 0.0f32;
    mono(&samples(len, |t| {
        let n = noise.next_sample();
        lp += 0.35 * (n - lp);
        hp += 0.05 * (lp - hp);
        let hiss = lp - hp;
        // A buzzy "voice" whose pitch wanders, chopped into syllables.
        phase += TAU * (140.0 + 40.0 * (TAU * 3.0 * t).sin()) / RATE as f32;
        let syllable = ((TAU * 6.0 * t).sin() * 0.5 + 0.5).powi(2);
        let voice = phase.sin().signum() * 0.25 * syllable * (TAU * 900.0 * t).sin();
        let gate = if t < 0.06 || t > len - 0.08 { 0.6 } else { 0.15 };
        (gate * hiss + if (0.08..len - 0.1).contains(&t) { voice } else { 0.0 }) * (1.0 - t / len).max(0.0).sqrt()
    }))
}

/// A guard's bark: a voiced "hey!" (two formants over a falling pitch); sharper when chasing.
pub fn bark(chasing: bool) -> StaticSoundData {
    let (len, f0) = if chasing { (0.35, 210.0) } else { (0.45, 160.0) };
    let mut phase = 0.0f32;
    mono(&samples(len, |t| {
        phase += TAU * f0 * (1.0 - 0.3 * t / len) / RATE as f32;
        let voice = phase.sin().signum() * 0.3;
        let formants = (TAU * 700.0 * t).sin() * 0.6 + (TAU * 1200.0 * t).sin() * 0.4;
        0.5 * voice * formants * (t / 0.02).min(1.0) * (1.0 - t / len)
    }))
}

/// What the contact sound follows, written by the game thread.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactParams {
    /// Contact force, N (0 = free space).
    pub force_n: f32,
    /// Sliding speed of the stylus over the surface, m/s.
    pub slip_m_per_s: f32,
    /// 0 (soft) … 1 (hard): higher, shorter taps and brighter scrapes.
    pub hardness: f32,
    /// 0 (smooth) … 1 (rough): louder, grainier scrapes.
    pub roughness: f32,
    /// Ridges the stylus rides over per second (0 on a smooth surface): the scrape ticks with each.
    pub ridges_per_s: f32,
}

/// Controls a playing [`ContactSoundData`].
pub struct ContactHandle {
    params: triple_buffer::Input<ContactParams>,
    taps: Arc<AtomicU32>,
}

impl ContactHandle {
    /// Updates the contact.
    pub fn set(&mut self, p: ContactParams) {
        self.params.write(p);
    }

    /// Strikes a tap of `strength` (0..1), e.g. when the stylus hits the surface.
    pub fn tap(&self, strength: f32) {
        self.taps.store((strength.clamp(0.0, 1.0) * 1000.0) as u32 + 1, Ordering::Release);
    }
}

/// The contact sound: a scrape (noise through a resonant band-pass, level from force × sliding speed,
/// swelling once per ridge ridden over) and taps (a decaying resonance, pitch and decay from hardness).
pub struct ContactSoundData;

impl SoundData for ContactSoundData {
    type Error = std::convert::Infallible;
    type Handle = ContactHandle;

    fn into_sound(self) -> Result<(Box<dyn Sound>, Self::Handle), Self::Error> {
        let (input, output) = triple_buffer::triple_buffer(&ContactParams::default());
        let taps = Arc::new(AtomicU32::new(0));
        let sound = ContactSound {
            params: output,
            taps: taps.clone(),
            noise: Noise::new(3),
            band: [0.0; 2],
            level: 0.0,
            tap_amp: 0.0,
            tap_phase: 0.0,
            ridge_phase: 0.0,
            current: ContactParams::default(),
        };
        Ok((Box::new(sound), ContactHandle { params: input, taps }))
    }
}

struct ContactSound {
    params: triple_buffer::Output<ContactParams>,
    taps: Arc<AtomicU32>,
    noise: Noise,
    band: [f32; 2],
    level: f32,
    tap_amp: f32,
    tap_phase: f32,
    ridge_phase: f32,
    current: ContactParams,
}

impl Sound for ContactSound {
    fn on_start_processing(&mut self) {
        self.current = *self.params.read();
        let tap = self.taps.swap(0, Ordering::AcqRel);
        if tap > 0 {
            self.tap_amp = self.tap_amp.max(0.15 + 0.6 * (tap - 1) as f32 / 1000.0);
            self.tap_phase = 0.0;
        }
    }

    fn process(&mut self, out: &mut [Frame], dt: f64, _info: &Info) {
        let p = self.current;
        let dt = dt as f32;
        let target = if p.force_n > 0.0 {
            (p.force_n * p.slip_m_per_s * 4.0).min(1.0) * (0.35 + 0.65 * p.roughness)
        } else {
            0.0
        };
        let centre = 500.0 + 2500.0 * p.hardness + 4000.0 * p.slip_m_per_s.min(0.5);
        // State-variable band-pass: centre frequency and a fixed Q of about 2.
        let f = (2.0 * (std::f32::consts::PI * centre * dt).sin()).min(1.0);
        let q = 0.5;
        let tap_f = 600.0 + 1600.0 * p.hardness;
        let tap_decay = (-dt / (0.015 + 0.025 * p.hardness)).exp();
        // Ridges faster than 200 a second blur into the scrape; a negative or NaN rate is none.
        let ridge_step = TAU * p.ridges_per_s.clamp(0.0, 200.0) * dt;
        let ridged = ridge_step > 0.0;
        for frame in out {
            self.level += (target - self.level) * 0.002;
            let x = self.noise.next_sample() * (1.0 + p.roughness * self.noise.next_sample().abs());
            let [low, band] = &mut self.band;
            *low += f * *band;
            let high = x - *low - q * *band;
            *band += f * high;
            // Over ridges the scrape swells as the tip drops off each one: a sharp peak per ridge.
            let swell = if ridged {
                self.ridge_phase = (self.ridge_phase + ridge_step) % TAU;
                let crest = 0.5 + 0.5 * self.ridge_phase.cos();
                0.25 + 1.5 * crest * crest * crest * crest
            } else {
                1.0
            };
            let scrape = *band * self.level * swell;
            self.tap_phase += TAU * tap_f * dt;
            let tap = self.tap_amp * self.tap_phase.sin();
            self.tap_amp *= tap_decay;
            let s = (scrape + tap).clamp(-1.0, 1.0);
            *frame = Frame { left: s, right: s };
        }
    }

    fn finished(&self) -> bool {
        // Runs until its handle is dropped.
        Arc::strong_count(&self.taps) == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_one_shot_is_short_audible_and_bounded() {
        let all = [footstep(1), glass(), thud(), alarm(), bark(true), bark(false)].into_iter().chain(
            [
                Earcon::CopyArrived,
                Earcon::ReadyToFeel,
                Earcon::Right,
                Earcon::Wrong,
                Earcon::AlarmUp,
                Earcon::Won,
                Earcon::Lost,
            ]
            .map(earcon),
        );
        for s in all {
            let peak = s.frames.iter().map(|f| f.left.abs()).fold(0.0, f32::max);
            assert!(peak > 0.05 && peak <= 1.0, "peak {peak}");
            assert!(s.frames.len() < 2 * RATE as usize);
        }
    }

    #[test]
    fn distinct_earcons_sound_different() {
        assert_ne!(earcon(Earcon::Right).frames.len(), earcon(Earcon::Wrong).frames.len());
    }
}
