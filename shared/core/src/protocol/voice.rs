//! The walkie-talkie on the wire: Opus frames of 20 ms from a client to the server ([`ClientVoice`]) and
//! from the server to that client's partner ([`PartnerVoice`]), each on an unreliable channel of its own
//! ([`super::GameChannel::Voice`]) so a lost or late voice frame never holds up a game message.
//!
//! You need this module to change what a voice frame carries. The server never decodes the audio: it
//! checks the frame's shape here, the sender's rate, and relays it to the sender's partner only.

use bevy::prelude::*;
use bevy_replicon::{
    bytes::Bytes,
    postcard,
    shared::message::ctx::{ClientSendCtx, ServerReceiveCtx},
};
use serde::{Deserialize, Serialize};

/// The voice's sample rate, Hz (Opus's full band).
pub const VOICE_SAMPLE_RATE: u32 = 48_000;
/// Samples in one frame: 20 ms at [`VOICE_SAMPLE_RATE`].
pub const VOICE_FRAME_SAMPLES: usize = 960;
/// Frames a second at most from an honest client (one per 20 ms).
pub const VOICE_FRAMES_PER_S: f32 = 50.0;
/// Largest Opus packet a frame may carry, bytes: 20 ms at the 32 kb/s the clients use at most is 80
/// bytes; in-band FEC adds some. Far below one datagram.
pub const MAX_VOICE_BYTES: usize = 200;

/// 20 ms of one player's voice.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct VoiceFrame {
    /// Counts up by one per frame, across transmissions (wraps).
    pub seq: u16,
    /// The last frame of a transmission (push-to-talk released).
    pub end: bool,
    /// One Opus packet of [`VOICE_FRAME_SAMPLES`] samples, mono, at most [`MAX_VOICE_BYTES`].
    pub opus: Vec<u8>,
}

/// A client's voice frame, as the server reads it.
#[derive(Message, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ClientVoice {
    /// A frame within the limits.
    Frame(VoiceFrame),
    /// Bytes that were not one frame within the limits (made by the server's decoder, never sent): the
    /// frame is dropped and held against the sender.
    Malformed,
}

/// The partner's voice frame, relayed by the server.
#[derive(Message, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartnerVoice(pub VoiceFrame);

pub(super) fn serialize(_ctx: &mut ClientSendCtx<'_>, msg: &ClientVoice, out: &mut Vec<u8>) -> Result<()> {
    bevy_replicon::postcard_utils::to_extend_mut(msg, out)?;
    Ok(())
}

/// Never fails: what is not one frame within the limits becomes [`ClientVoice::Malformed`].
pub(super) fn deserialize(_ctx: &mut ServerReceiveCtx<'_>, bytes: &mut Bytes) -> Result<ClientVoice> {
    let all = std::mem::take(bytes);
    Ok(decode(&all))
}

/// Decodes one client voice message; anything that is not exactly one frame within the limits becomes
/// [`ClientVoice::Malformed`].
pub fn decode(bytes: &[u8]) -> ClientVoice {
    match postcard::take_from_bytes::<ClientVoice>(bytes) {
        Ok((ClientVoice::Frame(f), [])) if !f.opus.is_empty() && f.opus.len() <= MAX_VOICE_BYTES => {
            ClientVoice::Frame(f)
        }
        _ => ClientVoice::Malformed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_frame_round_trips_and_an_oversized_or_empty_one_is_malformed() {
        let frame = VoiceFrame { seq: 7, end: true, opus: vec![1; 80] };
        let bytes = postcard::to_allocvec(&ClientVoice::Frame(frame.clone())).unwrap();
        assert_eq!(decode(&bytes), ClientVoice::Frame(frame));
        let big = VoiceFrame { seq: 1, end: false, opus: vec![0; MAX_VOICE_BYTES + 1] };
        assert_eq!(decode(&postcard::to_allocvec(&ClientVoice::Frame(big)).unwrap()), ClientVoice::Malformed);
        let empty = VoiceFrame { seq: 1, end: false, opus: vec![] };
        assert_eq!(decode(&postcard::to_allocvec(&ClientVoice::Frame(empty)).unwrap()), ClientVoice::Malformed);
        let forged = postcard::to_allocvec(&ClientVoice::Malformed).unwrap();
        assert_eq!(decode(&forged), ClientVoice::Malformed);
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic_the_voice_decoder(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = decode(&bytes);
        }
    }
}
