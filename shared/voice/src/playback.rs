//! The partner's voice as a kira sound: the game thread hands received frames over a ring buffer sized up
//! front ([`VoiceHandle::push`]); the audio thread moves them into the [`JitterBuffer`], decodes one
//! frame each 20 ms of output and plays it. The sound card's clock is the playout clock, so the jitter
//! buffer's delay is all the waiting there is.
//!
//! You need this module to play a voice stream. On the audio thread nothing allocates, locks or logs:
//! the ring, the jitter buffer's slots and the decoder's state are all made before the sound starts;
//! what happened is counted in atomics the handle reads.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use heist_shared::protocol::voice::VoiceFrame;
use kira::Frame;
use kira::info::Info;
use kira::sound::{Sound, SoundData};

use crate::codec::{Decode, Decoder};
use crate::jitter::{JitterBuffer, JitterStats, Packet, Playout};
use crate::{VOICE_FRAME_SAMPLES, VOICE_SAMPLE_RATE, VoiceError};

/// Frames the ring between the game thread and the audio thread holds: 1.28 s, far more than arrive
/// between two audio blocks.
pub const RING_FRAMES: usize = 64;

#[derive(Default)]
struct Shared {
    played: AtomicU32,
    recovered: AtomicU32,
    concealed: AtomicU32,
    late: AtomicU32,
    transmissions: AtomicU32,
    delay: AtomicU32,
    errors: AtomicU32,
    audible: AtomicBool,
}

/// Builds the partner's voice sound (play it with `AudioEngine::play_partner`).
pub struct VoiceSoundData;

/// Feeds a playing [`VoiceSoundData`] and reads what it did.
pub struct VoiceHandle {
    packets: rtrb::Producer<Packet>,
    shared: Arc<Shared>,
    /// Frames the ring had no room for (the audio thread stalled).
    pub overflowed: u64,
}

impl VoiceHandle {
    /// Hands a received frame to the audio thread; a malformed one is dropped.
    pub fn push(&mut self, frame: &VoiceFrame) {
        let Some(packet) = Packet::of(frame) else { return };
        if self.packets.push(packet).is_err() {
            self.overflowed += 1;
        }
    }

    /// What the jitter buffer has done so far.
    pub fn stats(&self) -> JitterStats {
        let s = &self.shared;
        JitterStats {
            played: s.played.load(Ordering::Relaxed),
            recovered: s.recovered.load(Ordering::Relaxed),
            concealed: s.concealed.load(Ordering::Relaxed),
            late: s.late.load(Ordering::Relaxed),
            transmissions: s.transmissions.load(Ordering::Relaxed),
            delay: s.delay.load(Ordering::Relaxed) as u16,
        }
    }

    /// Frames that could not be decoded.
    pub fn decode_errors(&self) -> u32 {
        self.shared.errors.load(Ordering::Relaxed)
    }

    /// True while the partner's voice is being played.
    pub fn is_audible(&self) -> bool {
        self.shared.audible.load(Ordering::Relaxed)
    }
}

impl SoundData for VoiceSoundData {
    type Error = VoiceError;
    type Handle = VoiceHandle;

    fn into_sound(self) -> Result<(Box<dyn Sound>, Self::Handle), Self::Error> {
        let (producer, consumer) = rtrb::RingBuffer::new(RING_FRAMES);
        let shared = Arc::new(Shared::default());
        let sound = VoiceSound {
            packets: consumer,
            jitter: JitterBuffer::default(),
            decoder: Decoder::new()?,
            frame: [0.0; VOICE_FRAME_SAMPLES],
            pos: VOICE_FRAME_SAMPLES as f64,
            shared: shared.clone(),
        };
        Ok((Box::new(sound), VoiceHandle { packets: producer, shared, overflowed: 0 }))
    }
}

struct VoiceSound {
    packets: rtrb::Consumer<Packet>,
    jitter: JitterBuffer,
    decoder: Decoder,
    frame: [f32; VOICE_FRAME_SAMPLES],
    /// Position in `frame`, in 48 kHz samples.
    pos: f64,
    shared: Arc<Shared>,
}

impl VoiceSound {
    fn next_frame(&mut self) {
        let playout = self.jitter.pop();
        let decoded = match &playout {
            Playout::Frame(p) => self.decoder.decode(Decode::Packet(p.opus()), &mut self.frame),
            Playout::Recover(next) => self.decoder.decode(Decode::Recover(next.opus()), &mut self.frame),
            Playout::Conceal => self.decoder.decode(Decode::Conceal, &mut self.frame),
            Playout::Silence => {
                self.frame.fill(0.0);
                Ok(())
            }
        };
        if decoded.is_err() {
            // Counted, not logged: this is the audio thread.
            self.shared.errors.fetch_add(1, Ordering::Relaxed);
        }
        let stats = self.jitter.stats();
        let s = &self.shared;
        s.played.store(stats.played, Ordering::Relaxed);
        s.recovered.store(stats.recovered, Ordering::Relaxed);
        s.concealed.store(stats.concealed, Ordering::Relaxed);
        s.late.store(stats.late, Ordering::Relaxed);
        s.transmissions.store(stats.transmissions, Ordering::Relaxed);
        s.delay.store(u32::from(stats.delay), Ordering::Relaxed);
        s.audible.store(playout != Playout::Silence, Ordering::Relaxed);
    }
}

impl Sound for VoiceSound {
    fn on_start_processing(&mut self) {
        while let Ok(p) = self.packets.pop() {
            self.jitter.push(p);
        }
    }

    fn process(&mut self, out: &mut [Frame], dt: f64, _info: &Info) {
        let step = dt * f64::from(VOICE_SAMPLE_RATE);
        let n = VOICE_FRAME_SAMPLES as f64;
        for f in out.iter_mut() {
            while self.pos >= n {
                self.pos -= n;
                self.next_frame();
            }
            *f = Frame::from_mono(self.frame[self.pos as usize]);
            self.pos += step;
        }
    }

    fn finished(&self) -> bool {
        // Plays until its handle is dropped.
        Arc::strong_count(&self.shared) == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::Encoder;

    #[test]
    fn frames_pushed_on_the_game_thread_are_played_in_order_after_the_playout_delay() {
        let (mut sound, mut handle) = VoiceSoundData.into_sound().expect("sound");
        let mut enc = Encoder::new().expect("encoder");
        let tone: Vec<[f32; VOICE_FRAME_SAMPLES]> = (0..10)
            .map(|f| std::array::from_fn(|i| ((f * VOICE_FRAME_SAMPLES + i) as f32 * 0.06).sin() * 0.4))
            .collect();
        for (i, t) in tone.iter().enumerate() {
            let opus = enc.encode(t).expect("encodes").to_vec();
            handle.push(&VoiceFrame { seq: i as u16, end: i == 9, opus });
        }
        let info = kira::info::MockInfoBuilder::new().build();
        sound.on_start_processing();
        let mut out = vec![Frame::ZERO; VOICE_FRAME_SAMPLES * 12];
        sound.process(&mut out, 1.0 / f64::from(VOICE_SAMPLE_RATE), &info);
        let energy: f32 = out.iter().map(|f| f.left * f.left).sum();
        assert!(energy > 100.0, "the tone is heard: {energy}");
        let stats = handle.stats();
        assert_eq!((stats.played, stats.transmissions), (10, 1), "{stats:?}");
        assert!(!handle.is_audible(), "the end frame was played");
        assert_eq!(handle.decode_errors(), 0);
    }
}
