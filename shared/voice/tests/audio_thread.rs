//! The audio thread's share of the walkie-talkie — taking frames off the ring, the jitter buffer,
//! decoding, concealing, resampling to the output rate — never allocates, also when frames are lost,
//! late, out of order or garbage (checked with `assert_no_alloc` as the test's global allocator).

use assert_no_alloc::{AllocDisabler, assert_no_alloc};
use heist_shared::protocol::voice::VoiceFrame;
use heist_voice::VOICE_FRAME_SAMPLES;
use heist_voice::codec::Encoder;
use heist_voice::playback::VoiceSoundData;
use kira::Frame;
use kira::sound::SoundData;

#[global_allocator]
static ALLOCATOR: AllocDisabler = AllocDisabler;

#[test]
fn playing_a_lossy_out_of_order_stream_with_garbage_never_allocates_on_the_audio_thread() {
    let (mut sound, mut handle) = VoiceSoundData.into_sound().expect("the sound");
    let mut enc = Encoder::new().expect("encoder");
    // Two seconds of a tone, numbered; every seventh lost, pairs swapped, a garbage frame now and then.
    let mut frames: Vec<VoiceFrame> = (0..100u16)
        .map(|f| {
            let pcm: [f32; VOICE_FRAME_SAMPLES] =
                std::array::from_fn(|i| ((usize::from(f) * VOICE_FRAME_SAMPLES + i) as f32 * 0.05).sin() * 0.4);
            VoiceFrame { seq: f, end: f == 99, opus: enc.encode(&pcm).expect("encodes").to_vec() }
        })
        .filter(|f| f.seq % 7 != 3)
        .collect();
    for pair in frames.chunks_mut(2).step_by(3) {
        pair.reverse();
    }
    for f in frames.iter_mut().step_by(11) {
        f.opus = vec![0xff; 40];
    }
    let info = kira::info::MockInfoBuilder::new().build();
    // 44.1 kHz output, in blocks of 441 frames, as a sound card might ask.
    let dt = 1.0 / 44_100.0;
    let mut out = vec![Frame::ZERO; 441];
    let mut next = frames.iter();
    let mut heard = 0.0f32;
    assert_no_alloc(|| {
        for block in 0..300 {
            // Two frames arrive every 40 ms (every fourth block of 10 ms), in a burst.
            if block % 4 == 0 {
                for f in next.by_ref().take(2) {
                    handle.push(f);
                }
            }
            sound.on_start_processing();
            sound.process(&mut out, dt, &info);
            heard += out.iter().map(|f| f.left.abs()).sum::<f32>();
        }
    });
    let stats = handle.stats();
    assert!(heard > 100.0, "the stream was heard: {heard}");
    assert!(stats.played > 50 && stats.recovered + stats.concealed > 5, "{stats:?}");
    assert!(handle.decode_errors() > 0, "the garbage frames were counted");
}
