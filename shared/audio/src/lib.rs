//! The museum's sounds for both Phantom Heist clients: kira 0.12 used directly, with binaural placement
//! and synthesized sounds.
//!
//! You need this crate to play anything. [`AudioEngine`] owns kira's manager (sound card, or memory
//! when there is none or in tests), a pool of binaural voices (sub-tracks with the [`binaural`] effect),
//! one voice for speech straight ahead, and the endless contact sound placed at the workbench. The game
//! side maps what happens to the museum's cues with [`museum`] and plays them with
//! [`AudioEngine::play_cue`] (or any sound with [`AudioEngine::play_at`]) at an offset in the listener's
//! frame; [`listener_offset`] turns a museum floor position into one.
#![warn(missing_docs)]

pub mod backend;
pub mod binaural;
pub mod hrir;
pub mod museum;
pub mod synth;

/// Audio could not start (the reason, for the player).
#[derive(Debug, thiserror::Error)]
#[error("audio: {0}")]
pub struct AudioError(pub String);

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::{Vec2, Vec3};
use kira::sound::static_sound::StaticSoundData;
use kira::track::{TrackBuilder, TrackHandle};
use kira::{AudioManager, AudioManagerSettings};

use self::backend::{Capture, CaptureBackend, CaptureSettings};
use self::binaural::{BinauralBuilder, BinauralHandle, Placement, Spatializer};
use self::synth::{ContactHandle, ContactParams, ContactSoundData, Earcon};

/// Where the sound goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AudioOutput {
    /// The default sound card (feature `sound-card`); falls back to memory when there is none.
    SoundCard,
    /// Rendered in real time by a thread into memory (and into a WAV file when one is named).
    Background(Option<PathBuf>),
    /// Rendered only when a test asks, through [`AudioEngine::capture`].
    Manual,
}

/// How sources are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpatialMode {
    /// HRTF convolution with the spherical-head HRIR sphere.
    Hrtf,
    /// Interaural time and level difference only.
    TimeLevel,
}

/// Settings of the audio engine.
#[derive(Clone, Debug)]
pub struct AudioSettings {
    /// Output (default: the sound card).
    pub output: AudioOutput,
    /// Placement (default HRTF).
    pub spatial: SpatialMode,
    /// Binaural voices for one-shots (default 12).
    pub voices: usize,
    /// Sample rate when rendering to memory, Hz (default 48 000).
    pub sample_rate: u32,
}

impl Default for AudioSettings {
    fn default() -> Self {
        Self { output: AudioOutput::SoundCard, spatial: SpatialMode::Hrtf, voices: 12, sample_rate: synth::RATE }
    }
}

enum Manager {
    Memory(AudioManager<CaptureBackend>),
    #[cfg(feature = "sound-card")]
    Card(AudioManager<kira::backend::cpal::CpalBackend>),
}

impl Manager {
    fn add_sub_track(&mut self, builder: TrackBuilder) -> Result<TrackHandle, AudioError> {
        let r = match self {
            Self::Memory(m) => m.add_sub_track(builder),
            #[cfg(feature = "sound-card")]
            Self::Card(m) => m.add_sub_track(builder),
        };
        r.map_err(|e| AudioError(format!("no room for a track: {e}")))
    }
}

struct Voice {
    track: TrackHandle,
    place: BinauralHandle,
}

/// Something the engine played, for the log and for tests.
#[derive(Clone, Debug, PartialEq)]
pub struct Cue {
    /// What it was.
    pub what: String,
    /// Where, in the listener's frame (m); zero for earcons.
    pub offset: Vec3,
}

/// Renders a memory output in real time on its own thread (and into a WAV file when asked).
struct Pump {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Pump {
    fn start(capture: Capture, wav: Option<PathBuf>) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("audio-pump".into())
            .spawn(move || {
                let rate = capture.sample_rate();
                let mut kept = Vec::new();
                let start = Instant::now();
                let mut rendered = 0u64;
                // Ten minutes at most are kept for the WAV file.
                let limit = rate as usize * 600;
                while !flag.load(Ordering::Acquire) {
                    let due = (start.elapsed().as_secs_f64() * rate as f64) as u64;
                    if due > rendered {
                        let n = (due - rendered).min(rate as u64) as usize;
                        let frames = capture.render(n);
                        rendered += n as u64;
                        if wav.is_some() && kept.len() < limit {
                            kept.extend(frames);
                        }
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                if let Some(path) = wav {
                    match backend::write_wav(&path, rate, &kept) {
                        Ok(()) => {
                            log::info!("audio written to {} ({:.1} s)", path.display(), kept.len() as f64 / rate as f64)
                        }
                        Err(e) => log::error!("could not write {}: {e}", path.display()),
                    }
                }
            })
            .ok();
        Self { stop, thread }
    }
}

impl Drop for Pump {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The volumes of the engine's groups, decibels (0 = as synthesized; [`kira::Decibels::SILENCE`] mutes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Volumes {
    /// Speech.
    pub speech_db: f32,
    /// The museum's sounds and the contact sound.
    pub sound_db: f32,
    /// Earcons.
    pub earcon_db: f32,
    /// The partner's voice (walkie-talkie).
    pub voice_db: f32,
}

/// The audio engine (see the module docs).
pub struct AudioEngine {
    /// Kept for its life: dropping the manager stops the sound.
    _manager: Manager,
    spatializer: Spatializer,
    voices: Vec<Voice>,
    next: usize,
    speech: Voice,
    earcons: TrackHandle,
    partner: Voice,
    /// Speech waiting to be said, and the line being said.
    speech_queue: std::collections::VecDeque<StaticSoundData>,
    saying: Option<kira::sound::static_sound::StaticSoundHandle>,
    contact: Option<ContactHandle>,
    capture: Option<Capture>,
    _pump: Option<Pump>,
    footsteps: Vec<StaticSoundData>,
    glass: StaticSoundData,
    thud: StaticSoundData,
    alarm: StaticSoundData,
    /// Every cue played, oldest first (bounded to the last 4096).
    pub played: Vec<Cue>,
}

/// Where the speech voice sits: just ahead of the listener.
pub const SPEECH_OFFSET: Vec3 = Vec3::new(0.0, 0.0, -0.8);
/// Lines of speech that may wait to be said; past this the oldest is dropped.
pub const MAX_QUEUED_SPEECH: usize = 32;
/// Where the partner's voice sits until it is placed: a radio just below and ahead.
pub const PARTNER_OFFSET: Vec3 = Vec3::new(0.1, -0.2, -0.3);
/// Where the contact sound sits: the copy on the workbench, ahead and below.
pub const CONTACT_OFFSET: Vec3 = Vec3::new(0.0, -0.3, -0.45);

impl AudioEngine {
    /// Starts the engine.
    pub fn new(settings: &AudioSettings) -> Result<Self, AudioError> {
        // The sphere is loaded either way, so HRTF can be turned on and off while playing.
        let bytes = hrir::sphere_bytes(settings.sample_rate);
        let spatializer = match hrtf::HrirSphere::new(std::io::Cursor::new(bytes), settings.sample_rate) {
            Ok(s) => Spatializer::hrtf(s, settings.spatial == SpatialMode::Hrtf),
            Err(e) => {
                log::warn!("audio: HRIR sphere unusable ({e:?}); using time and level differences");
                Spatializer::time_level()
            }
        };
        let (mut manager, capture, pump) = Self::open(settings)?;
        let voice = |manager: &mut Manager, at: Vec3| -> Result<Voice, AudioError> {
            let mut builder = TrackBuilder::new();
            let place = builder.add_effect(BinauralBuilder::new(spatializer.clone(), Placement { offset: at }));
            Ok(Voice { track: manager.add_sub_track(builder)?, place })
        };
        let voices =
            (0..settings.voices.max(1)).map(|_| voice(&mut manager, Vec3::NEG_Z)).collect::<Result<Vec<_>, _>>()?;
        let speech = voice(&mut manager, SPEECH_OFFSET)?;
        let partner = voice(&mut manager, PARTNER_OFFSET)?;
        let earcons = manager.add_sub_track(TrackBuilder::new())?;
        let mut contact_voice = voice(&mut manager, CONTACT_OFFSET)?;
        let contact = contact_voice.track.play(ContactSoundData).ok();
        // The contact voice's track lives as long as its handle: it is kept last among the voices.
        let mut voices = voices;
        voices.push(contact_voice);
        Ok(Self {
            _manager: manager,
            spatializer,
            voices,
            next: 0,
            speech,
            earcons,
            partner,
            speech_queue: std::collections::VecDeque::new(),
            saying: None,
            contact,
            capture,
            _pump: pump,
            footsteps: (1..=4).map(synth::footstep).collect(),
            glass: synth::glass(),
            thud: synth::thud(),
            alarm: synth::alarm(),
            played: Vec::new(),
        })
    }

    fn open(settings: &AudioSettings) -> Result<(Manager, Option<Capture>, Option<Pump>), AudioError> {
        let memory = |pump: Option<Option<PathBuf>>| -> Result<(Manager, Option<Capture>, Option<Pump>), AudioError> {
            let (backend_settings, capture) = CaptureSettings::new(settings.sample_rate);
            let manager = AudioManager::<CaptureBackend>::new(AudioManagerSettings {
                backend_settings,
                capacities: Default::default(),
                main_track_builder: Default::default(),
                internal_buffer_size: 128,
            })
            .map_err(|e| AudioError(format!("{e:?}")))?;
            let pump = pump.map(|wav| Pump::start(capture.clone(), wav));
            Ok((Manager::Memory(manager), Some(capture), pump))
        };
        match &settings.output {
            AudioOutput::Manual => memory(None),
            AudioOutput::Background(wav) => memory(Some(wav.clone())),
            AudioOutput::SoundCard => {
                #[cfg(feature = "sound-card")]
                {
                    match AudioManager::<kira::backend::cpal::CpalBackend>::new(AudioManagerSettings::default()) {
                        Ok(m) => return Ok((Manager::Card(m), None, None)),
                        Err(e) => log::warn!("audio: no sound card ({e}); rendering into memory instead"),
                    }
                }
                #[cfg(not(feature = "sound-card"))]
                log::warn!("audio: built without the sound-card feature; rendering into memory instead");
                memory(Some(None))
            }
        }
    }

    /// The memory output, when the engine renders into memory.
    pub fn capture(&self) -> Option<&Capture> {
        self.capture.as_ref()
    }

    fn note(&mut self, what: &str, offset: Vec3) {
        if self.played.len() >= 4096 {
            self.played.drain(..1024);
        }
        self.played.push(Cue { what: what.to_owned(), offset });
    }

    /// Plays `sound` from `offset` (listener frame, m).
    pub fn play_at(&mut self, sound: StaticSoundData, offset: Vec3, what: &str) {
        // The last voice is the contact sound's; one-shots take the others in turn.
        let n = self.voices.len() - 1;
        let voice = &mut self.voices[self.next % n];
        self.next = (self.next + 1) % n;
        voice.place.set(Placement { offset });
        if let Err(e) = voice.track.play(sound) {
            log::warn!("audio: {e}");
        }
        self.note(what, offset);
    }

    /// A footstep from `offset`; `loudness` 0..1.
    pub fn footstep(&mut self, offset: Vec3, loudness: f32, what: &str) {
        let mut s = self.footsteps[self.played.len() % self.footsteps.len()].clone();
        s.settings.volume = kira::Value::Fixed(kira::Decibels(20.0 * loudness.clamp(0.05, 1.0).log10()));
        self.play_at(s, offset, what);
    }

    /// Plays a museum cue (from [`museum`]) at `offset`, where the listener hears its floor point and
    /// height (listener frame, m).
    pub fn play_cue(&mut self, cue: &museum::MuseumCue, offset: Vec3) {
        use museum::Sound;
        match cue.sound {
            Sound::Glass => self.play_at(self.glass.clone(), offset, cue.what),
            Sound::Thud => self.play_at(self.thud.clone(), offset, cue.what),
            Sound::Alarm => self.play_at(self.alarm.clone(), offset, cue.what),
            Sound::Step { volume } => self.footstep(offset, volume, cue.what),
            Sound::Bark { chasing } => self.play_at(synth::bark(chasing), offset, cue.what),
            Sound::Radio => self.play_at(synth::radio_squawk(), offset, cue.what),
        }
    }

    /// An earcon, centred in the head.
    pub fn earcon(&mut self, e: Earcon) {
        if let Err(err) = self.earcons.play(synth::earcon(e)) {
            log::warn!("audio: {err}");
        }
        self.note(&format!("earcon {e:?}"), Vec3::ZERO);
    }

    /// Sets the groups' volumes (they glide there in 50 ms).
    pub fn set_volumes(&mut self, v: Volumes) {
        let tween = kira::Tween { duration: Duration::from_millis(50), ..Default::default() };
        let db = |x: f32| kira::Decibels(x.max(kira::Decibels::SILENCE.0));
        self.speech.track.set_volume(db(v.speech_db), tween);
        for voice in &mut self.voices {
            voice.track.set_volume(db(v.sound_db), tween);
        }
        self.earcons.set_volume(db(v.earcon_db), tween);
        self.partner.track.set_volume(db(v.voice_db), tween);
    }

    /// Turns HRTF placement on (or back to time and level differences) for every voice.
    pub fn set_hrtf(&mut self, on: bool) {
        self.spatializer.set_hrtf(on);
    }

    /// True when sources are placed with the HRTF.
    pub fn uses_hrtf(&self) -> bool {
        self.spatializer.uses_hrtf()
    }

    /// Plays a stream (the partner's voice) on the partner's voice, placed by [`AudioEngine::place_partner`].
    pub fn play_partner<D: kira::sound::SoundData>(&mut self, data: D) -> Result<D::Handle, AudioError> {
        self.note("partner voice", PARTNER_OFFSET);
        self.partner.track.play(data).map_err(|e| AudioError(format!("the partner's voice: {e}")))
    }

    /// Moves the partner's voice to `offset` (listener frame, m).
    pub fn place_partner(&mut self, offset: Vec3) {
        self.partner.place.set(Placement { offset });
    }

    /// Speech, from just ahead, 6 dB down (espeak-ng speaks at full scale; earcons and the museum mix in).
    /// Lines are said one after the other, never over each other: each waits for the one before to end
    /// (call [`AudioEngine::update`] every frame to start the next).
    pub fn speak(&mut self, mut sound: StaticSoundData) {
        sound.settings.volume = kira::Value::Fixed(kira::Decibels(-6.0));
        if self.speech_queue.len() >= MAX_QUEUED_SPEECH {
            log::warn!("audio: {MAX_QUEUED_SPEECH} lines wait to be said; the oldest is dropped");
            self.speech_queue.pop_front();
        }
        self.speech_queue.push_back(sound);
        self.update();
    }

    /// Starts the next line of speech when the one being said has ended.
    pub fn update(&mut self) {
        use kira::sound::PlaybackState;
        let busy = self.saying.as_ref().is_some_and(|h| h.state() != PlaybackState::Stopped);
        if busy {
            return;
        }
        self.saying = None;
        if let Some(next) = self.speech_queue.pop_front() {
            match self.speech.track.play(next) {
                Ok(handle) => self.saying = Some(handle),
                Err(e) => log::warn!("audio: {e}"),
            }
            self.note("speech", SPEECH_OFFSET);
        }
    }

    /// True while speech is being said or waits to be.
    pub fn is_speaking(&self) -> bool {
        !self.speech_queue.is_empty()
            || self.saying.as_ref().is_some_and(|h| h.state() != kira::sound::PlaybackState::Stopped)
    }

    /// Follows the haptic contact with the contact sound.
    pub fn contact(&mut self, params: ContactParams) {
        if let Some(c) = self.contact.as_mut() {
            c.set(params);
        }
    }

    /// Strikes the contact sound (the stylus hit the surface), `strength` 0..1.
    pub fn tap(&mut self, strength: f32) {
        if let Some(c) = self.contact.as_ref() {
            c.tap(strength);
        }
        self.note("tap", CONTACT_OFFSET);
    }
}

/// The offset of museum floor point `p` from a listener at floor point `at` facing +y of the floor
/// (the museum's north), in the listener's frame (+x right, −z ahead), ears 1.6 m above the floor.
pub fn listener_offset(at: Vec2, p: Vec2, height_m: f32) -> Vec3 {
    let d = p - at;
    Vec3::new(d.x, height_m - 1.6, -d.y)
}

#[cfg(test)]
mod tests;
