//! Opus for speech: 48 kHz mono, 20 ms frames, VoIP tuning, [`crate::BITRATE`], in-band FEC for
//! [`crate::EXPECTED_LOSS_PERCENT`] loss, DTX off (a transmission is short and every frame counts for
//! the jitter buffer).
//!
//! You need this module to change how voice is coded. The decoder is used on the audio thread: libopus
//! keeps all its state in the decoder, so decoding allocates nothing.

use opus::{Application, Bitrate, Channels};

use crate::{BITRATE, EXPECTED_LOSS_PERCENT, MAX_VOICE_BYTES, VOICE_FRAME_SAMPLES, VOICE_SAMPLE_RATE, VoiceError};

/// Turns 20 ms of speech into one Opus packet.
pub struct Encoder {
    inner: opus::Encoder,
    out: [u8; MAX_VOICE_BYTES],
}

impl Encoder {
    /// A speech encoder with the settings above.
    pub fn new() -> Result<Self, VoiceError> {
        let mut inner = opus::Encoder::new(VOICE_SAMPLE_RATE, Channels::Mono, Application::Voip)?;
        inner.set_bitrate(Bitrate::Bits(BITRATE))?;
        inner.set_inband_fec(true)?;
        inner.set_packet_loss_perc(EXPECTED_LOSS_PERCENT)?;
        inner.set_dtx(false)?;
        Ok(Self { inner, out: [0; MAX_VOICE_BYTES] })
    }

    /// Encodes exactly one frame ([`VOICE_FRAME_SAMPLES`] samples, −1..1) into a packet.
    pub fn encode(&mut self, frame: &[f32; VOICE_FRAME_SAMPLES]) -> Result<&[u8], VoiceError> {
        let n = self.inner.encode_float(frame, &mut self.out)?;
        Ok(&self.out[..n])
    }
}

/// How one 20 ms frame of output is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decode<'a> {
    /// From its own packet.
    Packet(&'a [u8]),
    /// The frame was lost: rebuilt from the FEC data of the packet after it.
    Recover(&'a [u8]),
    /// The frame was lost and nothing after it is here yet: Opus's loss concealment.
    Conceal,
}

/// Why a frame could not be decoded (plain data: the audio thread makes it without allocating).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// libopus refused the packet.
    Opus(opus::ErrorCode),
    /// The packet held this many samples, not one 20 ms frame.
    Length(usize),
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DecodeError::Opus(code) => write!(f, "opus: {}", code.description()),
            DecodeError::Length(n) => write!(f, "a packet of {n} samples, not {VOICE_FRAME_SAMPLES}"),
        }
    }
}

/// Turns packets back into speech, and fills lost frames.
pub struct Decoder {
    inner: opus::Decoder,
}

impl Decoder {
    /// A decoder for the clients' packets.
    pub fn new() -> Result<Self, VoiceError> {
        Ok(Self { inner: opus::Decoder::new(VOICE_SAMPLE_RATE, Channels::Mono)? })
    }

    /// Decodes one frame into `out`; on an error `out` is silence and the error is returned (the audio
    /// thread counts it, it does not log). Never allocates.
    pub fn decode(&mut self, how: Decode<'_>, out: &mut [f32; VOICE_FRAME_SAMPLES]) -> Result<(), DecodeError> {
        let r = match how {
            Decode::Packet(p) => self.inner.decode_float(p, out, false),
            Decode::Recover(next) => self.inner.decode_float(next, out, true),
            Decode::Conceal => self.inner.decode_float(&[], out, false),
        };
        let r = match r {
            Ok(n) if n == VOICE_FRAME_SAMPLES => return Ok(()),
            Ok(n) => DecodeError::Length(n),
            Err(e) => DecodeError::Opus(e.code()),
        };
        out.fill(0.0);
        Err(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tone(frame: usize, hz: f32) -> [f32; VOICE_FRAME_SAMPLES] {
        std::array::from_fn(|i| {
            let t = (frame * VOICE_FRAME_SAMPLES + i) as f32 / VOICE_SAMPLE_RATE as f32;
            0.5 * (std::f32::consts::TAU * hz * t).sin()
        })
    }

    fn rms(x: &[f32]) -> f32 {
        (x.iter().map(|s| s * s).sum::<f32>() / x.len() as f32).sqrt()
    }

    #[test]
    fn speech_band_tone_survives_a_round_trip_within_the_bit_rate() {
        let (mut enc, mut dec) = (Encoder::new().expect("encoder"), Decoder::new().expect("decoder"));
        let mut out = [0.0; VOICE_FRAME_SAMPLES];
        let mut bytes = 0;
        for f in 0..50 {
            let p = enc.encode(&tone(f, 440.0)).expect("encodes").to_vec();
            bytes += p.len();
            assert!(p.len() <= MAX_VOICE_BYTES);
            dec.decode(Decode::Packet(&p), &mut out).expect("decodes");
        }
        let kbps = bytes as f32 * 8.0 / 1000.0;
        assert!(kbps <= 32.0, "{kbps} kb/s over one second");
        assert!((rms(&out) - 0.354).abs() < 0.05, "the tone's level comes back: {}", rms(&out));
    }

    #[test]
    fn a_lost_frame_is_recovered_from_the_next_packets_fec_or_concealed() {
        let (mut enc, mut dec) = (Encoder::new().expect("encoder"), Decoder::new().expect("decoder"));
        let packets: Vec<Vec<u8>> = (0..20).map(|f| enc.encode(&tone(f, 300.0)).expect("encodes").to_vec()).collect();
        let mut out = [0.0; VOICE_FRAME_SAMPLES];
        for p in &packets[..10] {
            dec.decode(Decode::Packet(p), &mut out).expect("decodes");
        }
        dec.decode(Decode::Recover(&packets[11]), &mut out).expect("FEC");
        assert!(rms(&out) > 0.1, "the lost frame is rebuilt, not silent: {}", rms(&out));
        dec.decode(Decode::Packet(&packets[11]), &mut out).expect("decodes");
        dec.decode(Decode::Conceal, &mut out).expect("conceals");
        assert!(rms(&out) > 0.05, "concealment continues the sound: {}", rms(&out));
        assert!(dec.decode(Decode::Packet(&[0xff; 3]), &mut out).is_err(), "garbage is an error, not a panic");
    }
}
