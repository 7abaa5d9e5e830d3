//! Speech for everything: menu items, state changes, the briefing, results.
//!
//! You need this module to say something. Text goes to a worker thread that runs `espeak-ng` (Debian
//! package `espeak-ng`) and returns a WAV, decoded here into kira sound data so the audio module can
//! place it and tests can hear it. Every line is also written to the log ("SAY: …"), so nothing is lost
//! when espeak-ng is missing; the first failure says how to install it.

use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, Sender};

use kira::sound::static_sound::StaticSoundData;

use crate::error::ClientError;

/// Decodes a 16-bit PCM WAV as espeak-ng writes it to a pipe (its size fields are left unset, so
/// the data runs to the end of the bytes); returns (sample rate, mono samples).
pub fn decode_wav(bytes: &[u8]) -> Result<(u32, Vec<f32>), ClientError> {
    let bad = |what: &str| ClientError::Speech(format!("espeak-ng's WAV: {what}"));
    if bytes.len() < 12 || &bytes[0..4] != b"RIFF" || &bytes[8..12] != b"WAVE" {
        return Err(bad("no RIFF/WAVE header"));
    }
    let (mut at, mut format) = (12, None);
    while at + 8 <= bytes.len() {
        let id = &bytes[at..at + 4];
        let len = u32::from_le_bytes([bytes[at + 4], bytes[at + 5], bytes[at + 6], bytes[at + 7]]) as usize;
        let body = at + 8;
        if id == b"fmt " {
            let f = bytes.get(body..body + 16).ok_or_else(|| bad("fmt chunk cut short"))?;
            let channels = u16::from_le_bytes([f[2], f[3]]).max(1) as usize;
            let rate = u32::from_le_bytes([f[4], f[5], f[6], f[7]]);
            let bits = u16::from_le_bytes([f[14], f[15]]);
            if u16::from_le_bytes([f[0], f[1]]) != 1 || bits != 16 || rate == 0 {
                return Err(bad(&format!("not 16-bit PCM ({bits} bits at {rate} Hz)")));
            }
            format = Some((channels, rate));
        } else if id == b"data" {
            let (channels, rate) = format.ok_or_else(|| bad("data before fmt"))?;
            let end = body.saturating_add(len).min(bytes.len());
            let samples = bytes[body..end]
                .chunks_exact(2 * channels)
                .map(|c| i16::from_le_bytes([c[0], c[1]]) as f32 / 32768.0)
                .collect();
            return Ok((rate, samples));
        }
        at = body.saturating_add(len + (len & 1));
    }
    Err(bad("no data chunk"))
}

/// espeak-ng's default speech rate, words per minute.
pub const DEFAULT_RATE: u32 = 175;

/// Runs espeak-ng on `text` at `rate` words per minute and returns the speech.
pub fn synthesize(text: &str, rate: u32) -> Result<StaticSoundData, ClientError> {
    let rate = rate.to_string();
    let out = Command::new("espeak-ng").args(["--stdout", "-s", &rate, "--", text]).output().map_err(|e| {
        ClientError::Speech(format!("could not run espeak-ng ({e}); install it with `apt-get install espeak-ng`"))
    })?;
    if !out.status.success() {
        return Err(ClientError::Speech(format!("espeak-ng failed: {}", String::from_utf8_lossy(&out.stderr).trim())));
    }
    let (rate, samples) = decode_wav(&out.stdout)?;
    let mut data = crate::audio::synth::mono(&samples);
    data.sample_rate = rate;
    Ok(data)
}

/// A spoken line, ready to play.
pub struct Utterance {
    /// What was said.
    pub text: String,
    /// The speech, or why there is none.
    pub audio: Result<StaticSoundData, ClientError>,
}

/// The speech worker: lines in, utterances out, in order.
pub struct Speaker {
    to_worker: Sender<(String, Option<u32>)>,
    rate: Arc<AtomicU32>,
    from_worker: Receiver<Utterance>,
    last: Option<(String, Option<u32>)>,
    warned: bool,
    /// Lines sent to the worker, and lines back from it.
    queued: (u64, u64),
    /// Every line said, oldest first.
    pub said: Vec<String>,
}

impl Default for Speaker {
    fn default() -> Self {
        Self::new()
    }
}

impl Speaker {
    /// Starts the worker thread.
    pub fn new() -> Self {
        let (to_worker, rx) = std::sync::mpsc::channel::<(String, Option<u32>)>();
        let (tx, from_worker) = std::sync::mpsc::channel();
        let rate = Arc::new(AtomicU32::new(DEFAULT_RATE));
        let worker_rate = rate.clone();
        let spawned = std::thread::Builder::new().name("speech".into()).spawn(move || {
            for (text, slower) in rx {
                let rate = worker_rate.load(Ordering::Relaxed);
                let audio = synthesize(&text, slower.map_or(rate, |s| s.min(rate)));
                if tx.send(Utterance { text, audio }).is_err() {
                    break;
                }
            }
        });
        if let Err(e) = spawned {
            log::error!("speech: could not start its thread: {e}");
        }
        Self { to_worker, rate, from_worker, last: None, warned: false, queued: (0, 0), said: Vec::new() }
    }

    /// Speaks the lines said from now on at `wpm` words per minute.
    pub fn set_rate(&mut self, wpm: u32) {
        self.rate.store(wpm, Ordering::Relaxed);
    }

    /// Says `text` (queued behind earlier lines).
    pub fn say(&mut self, text: impl Into<String>) {
        self.say_at(text, None);
    }

    /// Says `text` at most at `wpm` words per minute (a join code, spelled slowly).
    pub fn say_slowly(&mut self, text: impl Into<String>, wpm: u32) {
        self.say_at(text, Some(wpm));
    }

    fn say_at(&mut self, text: impl Into<String>, slower: Option<u32>) {
        let text = text.into();
        // Printed once, as it is said (a screen reader reads the terminal); the log has it only on request.
        log::debug!("said: {text}");
        println!("{text}");
        self.said.push(text.clone());
        self.last = Some((text.clone(), slower));
        self.queue(text, slower);
    }

    /// Says `text` without printing it (a typed character said back: the terminal shows it already).
    pub fn speak_only(&mut self, text: impl Into<String>) {
        let text = text.into();
        log::debug!("said (not printed): {text}");
        self.queue(text, None);
    }

    fn queue(&mut self, text: String, slower: Option<u32>) {
        if self.to_worker.send((text, slower)).is_ok() {
            self.queued.0 += 1;
        }
    }

    /// Lines not yet synthesized.
    pub fn pending(&self) -> u64 {
        self.queued.0 - self.queued.1
    }

    /// Prints `text` for a screen reader without saying it (what the player hears already, or what
    /// speaking would drown: "Talking to Vive" while the microphone is open).
    pub fn print(&mut self, text: &str) {
        log::debug!("printed: {text}");
        println!("{text}");
    }

    /// Says the last line again.
    pub fn repeat(&mut self) {
        match self.last.clone() {
            Some((t, slower)) => self.say_at(t, slower),
            None => self.say("Nothing has been said yet."),
        }
    }

    /// The speech ready to play since the last call.
    pub fn ready(&mut self) -> Vec<StaticSoundData> {
        let mut out = Vec::new();
        while let Ok(u) = self.from_worker.try_recv() {
            self.queued.1 += 1;
            match u.audio {
                Ok(a) => out.push(a),
                Err(e) if !self.warned => {
                    log::error!("{e} (said only in the log: {:?})", u.text);
                    self.warned = true;
                }
                Err(_) => {}
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wav_with_unset_sizes_decodes_to_the_end() {
        let mut b = Vec::new();
        b.extend_from_slice(b"RIFF\xff\xff\xff\x7fWAVEfmt ");
        b.extend_from_slice(&16u32.to_le_bytes());
        b.extend_from_slice(&[1, 0, 1, 0]);
        b.extend_from_slice(&22050u32.to_le_bytes());
        b.extend_from_slice(&44100u32.to_le_bytes());
        b.extend_from_slice(&[2, 0, 16, 0]);
        b.extend_from_slice(b"data\x00\xf0\xff\x7f");
        for s in [0i16, 16384, -16384] {
            b.extend_from_slice(&s.to_le_bytes());
        }
        let (rate, samples) = decode_wav(&b).expect("decodes");
        assert_eq!(rate, 22050);
        assert_eq!(samples, vec![0.0, 0.5, -0.5]);
    }

    #[test]
    fn a_menu_item_is_spoken_and_heard() {
        use crate::audio::{AudioEngine, AudioOutput, AudioSettings};
        let mut audio = AudioEngine::new(&AudioSettings { output: AudioOutput::Manual, ..Default::default() })
            .expect("audio starts");
        let capture = audio.capture().expect("memory output").clone();
        let mut speaker = Speaker::new();
        speaker.say(crate::status::MenuItem::Ready.label());
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
        let speech = loop {
            if let Some(s) = speaker.ready().pop() {
                break s;
            }
            assert!(std::time::Instant::now() < deadline, "espeak-ng (scripts/deps.sh installs it) gave no speech");
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        assert!(speech.duration().as_secs_f64() > 1.0, "a sentence lasts over a second: {:?}", speech.duration());
        audio.speak(speech);
        let frames = capture.render(48_000);
        let loud = frames.iter().filter(|f| f.0.abs().max(f.1.abs()) > 0.02).count();
        assert!(loud > 4_800, "only {loud} audible frames in the first second");
        assert_eq!(speaker.said, vec![crate::status::MenuItem::Ready.label().to_owned()]);
    }

    #[test]
    fn a_broken_wav_says_what_is_wrong() {
        let err = decode_wav(b"RIFX....WAVE").unwrap_err().to_string();
        assert!(err.contains("no RIFF/WAVE header"), "{err}");
        let err = decode_wav(b"RIFF....WAVEdata\x04\x00\x00\x00abcd").unwrap_err().to_string();
        assert!(err.contains("data before fmt"), "{err}");
    }
}
