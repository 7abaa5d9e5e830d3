//! The sending side: push-to-talk opens the microphone, its samples are cut into 20 ms frames and coded;
//! releasing the key sends what is left as the transmission's last frame.
//!
//! You need this module to change when or how voice is sent. Takes the key's state and the time as
//! inputs (no clock of its own), returns the frames to send.

use heist_shared::protocol::voice::VoiceFrame;

use crate::codec::Encoder;
use crate::mic::Microphone;
use crate::{VOICE_FRAME_SAMPLES, VoiceError};

/// Most frames kept waiting to be sent (200 ms): after a stall the oldest speech is dropped rather than
/// sent late in a burst the server would cut anyway.
pub const MAX_BACKLOG_FRAMES: usize = 10;

/// A change of the transmission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TalkChange {
    /// Push-to-talk went down: the transmission started.
    Started,
    /// Push-to-talk went up: the last frame is sent.
    Stopped,
}

/// The sending side (see the module docs).
pub struct Transmitter {
    encoder: Encoder,
    mic: Microphone,
    talking: bool,
    buf: Vec<f32>,
    seq: u16,
    /// Frames sent since the start.
    pub sent: u64,
}

impl Transmitter {
    /// A transmitter on `mic`.
    pub fn new(mic: Microphone) -> Result<Self, VoiceError> {
        Ok(Self { encoder: Encoder::new()?, mic, talking: false, buf: Vec::new(), seq: 0, sent: 0 })
    }

    /// True while transmitting.
    pub fn is_talking(&self) -> bool {
        self.talking
    }

    /// True once a microphone file has been said whole since the transmission started.
    pub fn said_all(&self) -> bool {
        self.mic.said()
    }

    /// Steps to `now_s` with push-to-talk `down`; appends the frames to send to `out`.
    pub fn step(&mut self, down: bool, now_s: f64, out: &mut Vec<VoiceFrame>) -> Option<TalkChange> {
        let change = match (self.talking, down) {
            (false, true) => {
                self.mic.start(now_s);
                self.buf.clear();
                self.talking = true;
                Some(TalkChange::Started)
            }
            (true, false) => Some(TalkChange::Stopped),
            _ => None,
        };
        if !self.talking {
            return change;
        }
        self.mic.read(now_s, &mut self.buf);
        let excess = self.buf.len().saturating_sub(MAX_BACKLOG_FRAMES * VOICE_FRAME_SAMPLES);
        self.buf.drain(..excess);
        let whole = self.buf.len() / VOICE_FRAME_SAMPLES;
        for i in 0..whole {
            let mut frame = [0.0; VOICE_FRAME_SAMPLES];
            frame.copy_from_slice(&self.buf[i * VOICE_FRAME_SAMPLES..(i + 1) * VOICE_FRAME_SAMPLES]);
            self.send(&frame, false, out);
        }
        self.buf.drain(..whole * VOICE_FRAME_SAMPLES);
        if change == Some(TalkChange::Stopped) {
            // What is left, padded with silence, ends the transmission.
            let mut frame = [0.0; VOICE_FRAME_SAMPLES];
            frame[..self.buf.len()].copy_from_slice(&self.buf);
            self.buf.clear();
            self.send(&frame, true, out);
            self.talking = false;
        }
        change
    }

    fn send(&mut self, frame: &[f32; VOICE_FRAME_SAMPLES], end: bool, out: &mut Vec<VoiceFrame>) {
        match self.encoder.encode(frame) {
            Ok(opus) => {
                out.push(VoiceFrame { seq: self.seq, end, opus: opus.to_vec() });
                self.seq = self.seq.wrapping_add(1);
                self.sent += 1;
            }
            Err(e) => log::warn!("voice: a frame could not be coded: {e}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mic::WavMic;

    fn transmitter(seconds: f64) -> Transmitter {
        let n = (seconds * 48_000.0) as usize;
        let tone = (0..n).map(|i| (i as f32 * 0.05).sin() * 0.3).collect();
        Transmitter::new(Microphone::Wav(WavMic::from_samples(tone))).expect("encoder")
    }

    #[test]
    fn nothing_is_sent_until_push_to_talk_goes_down() {
        let mut tx = transmitter(1.0);
        let mut out = Vec::new();
        for i in 0..30 {
            assert_eq!(tx.step(false, f64::from(i) / 60.0, &mut out), None);
        }
        assert!(out.is_empty());
    }

    #[test]
    fn a_transmission_is_numbered_frames_of_20_ms_ending_with_a_marked_last_frame() {
        let mut tx = transmitter(1.0);
        let mut out = Vec::new();
        assert_eq!(tx.step(true, 0.0, &mut out), Some(TalkChange::Started));
        for i in 1..=30 {
            tx.step(true, f64::from(i) / 60.0, &mut out);
        }
        // Half a second: 25 whole frames.
        assert_eq!(out.len(), 25);
        assert_eq!(tx.step(false, 0.51, &mut out), Some(TalkChange::Stopped));
        assert_eq!(out.len(), 26, "what is left goes out as the last frame");
        assert!(out.iter().enumerate().all(|(i, f)| f.seq == i as u16 && f.end == (i == 25)));
        assert!(out.iter().all(|f| !f.opus.is_empty() && f.opus.len() <= crate::MAX_VOICE_BYTES));
        assert!(!tx.is_talking());
    }

    #[test]
    fn after_a_stall_only_the_latest_200_ms_are_sent() {
        let mut tx = transmitter(5.0);
        let mut out = Vec::new();
        tx.step(true, 0.0, &mut out);
        tx.step(true, 2.0, &mut out);
        assert_eq!(out.len(), MAX_BACKLOG_FRAMES);
    }
}
