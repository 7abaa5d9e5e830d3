//! The walkie-talkie end to end: an espeak-ng sentence is Vive's microphone; it goes through the real
//! server over loopback UDP (optionally through the link conditioner) to this client, whose audio is
//! rendered into memory. What Phantom hears is compared with what Vive said: the envelope's correlation
//! after alignment, and the mouth-to-ear latency.
//!
//! Every app and the audio are stepped by hand, one tick (1/60 s, 800 samples) at a time, so the figures
//! are the pipeline's own (framing, the apps' frame cadence, the relay, the jitter buffer, a tick of
//! output buffering), the same on any machine. Wall-clock figures: `cargo bench -p heist_voice`.

use std::time::Duration;

use bevy::prelude::*;
use client_haptic::audio::{AudioOutput, AudioSettings};
use client_haptic::settings::PlayerSettings;
use client_haptic::{PhantomSettings, settings::plugin::Settings};
use heist_conditioner::{Conditions, SteppedRelay};
use heist_server::demo::join;
use heist_server::{ServerOptions, build_server};
use heist_shared::protocol::{Role, TICK_HZ};
use heist_voice::measure::{align, envelope};
use heist_voice::plugin::Voice;
use heist_voice::{MicChoice, TalkMode, VoicePlugin, VoiceSettings};

const RATE: usize = 48_000;
const PER_TICK: usize = RATE / 60;
const SENTENCE: &str = "Phantom, the guard by the east door is gone. I am bringing the crown now.";

/// The sentence as espeak-ng says it, written to a WAV file; and its samples at 48 kHz.
fn sentence(name: &str) -> (std::path::PathBuf, Vec<f32>) {
    let path = std::env::temp_dir().join(format!("phantom-voice-{}-{name}.wav", std::process::id()));
    let status = std::process::Command::new("espeak-ng")
        .args(["-w"])
        .arg(&path)
        .arg(SENTENCE)
        .status()
        .expect("espeak-ng runs (scripts/deps.sh installs it)");
    assert!(status.success());
    let samples = heist_voice::mic::read_wav(&path).expect("the sentence reads");
    (path, samples)
}

struct Heard {
    latency_ms: f32,
    correlation: f32,
    stats: heist_voice::jitter::JitterStats,
    frames_sent: u64,
}

/// Vive says the sentence (open microphone); Phantom's client hears it; the link has `conditions`, dropping
/// datagrams by its seed.
fn talk_over(conditions: Option<(Conditions, u64)>, name: &str) -> Heard {
    let (wav, said) = sentence(name);
    let mut options = ServerOptions::local_test(5);
    let mut relay = conditions.map(|(c, seed)| SteppedRelay::bind(c, seed).expect("the relay binds"));
    if let Some(r) = &relay {
        options.advertise = Some(r.addr());
    }
    let mut server = build_server(options).expect("server starts");
    if let Some(r) = relay.as_mut() {
        r.forward_to(server.addr);
    }
    let vive_voice = VoiceSettings { mic: MicChoice::Wav(wav.clone()), mode: TalkMode::Open };
    let mut vive = join(&server, Role::Vive, |app| {
        app.insert_resource(vive_voice).add_plugins(VoicePlugin);
    })
    .expect("Vive joins");
    // Only the partner's voice is heard: speech, earcons and the museum are turned down in the settings.
    let quiet = PlayerSettings { speech_volume: 0, sound_volume: 0, earcon_volume: 0, ..Default::default() };
    let settings = PhantomSettings {
        audio: AudioSettings { output: AudioOutput::Manual, ..Default::default() },
        prefs: Settings::for_run(quiet),
        ..Default::default()
    };
    let mut phantom = join(&server, Role::Phantom, |app| {
        client_haptic::start(app, settings).expect("Phantom's client starts");
        app.insert_resource(VoiceSettings { mic: MicChoice::Off, mode: TalkMode::PushToTalk })
            .add_plugins((VoicePlugin, client_haptic::walkie::WalkiePlugin));
    })
    .expect("Phantom joins");
    let capture =
        phantom.world().non_send::<client_haptic::audio::AudioEngine>().capture().expect("memory output").clone();
    let tick = Duration::from_secs_f64(1.0 / TICK_HZ);
    let total_ticks = ((said.len() as f64 / RATE as f64 + 3.0) * TICK_HZ) as usize;
    let mut heard: Vec<f32> = Vec::with_capacity(total_ticks * PER_TICK);
    let mut mouth_tick = None;
    for t in 0..total_ticks {
        server.update();
        vive.update();
        phantom.update();
        if let Some(r) = relay.as_mut() {
            r.advance(tick).expect("the relay runs");
        }
        if mouth_tick.is_none()
            && vive.world().get_non_send::<Voice>().is_some_and(|v| v.tx.as_ref().is_ok_and(|tx| tx.is_talking()))
        {
            mouth_tick = Some(t);
        }
        heard.extend(capture.render(PER_TICK).iter().map(|(l, r)| 0.5 * (l + r)));
    }
    let mouth_tick = mouth_tick.expect("Vive's microphone opened once the server welcomed it");
    // Sample i of the sentence left Vive's mouth at tick `mouth_tick` + i/48000 s; sample j of what
    // Phantom heard was rendered in the update of tick j/800 and leaves the speaker during the next tick.
    let heard = &heard[mouth_tick * PER_TICK..];
    let hop = RATE / 400; // 2.5 ms windows
    let (lag, correlation) = align(&envelope(&said, hop), &envelope(heard, hop), 400);
    // (heist_voice::measure: RMS envelopes in 2.5 ms windows, the lag of best Pearson correlation.)
    let latency_ms = (lag * hop) as f32 / RATE as f32 * 1000.0 + 1000.0 / TICK_HZ as f32;
    let voice = phantom.world().non_send::<Voice>();
    let stats = voice.rx.as_ref().expect("Phantom plays the partner's voice").stats();
    let frames_sent = vive.world().non_send::<Voice>().tx.as_ref().map_or(0, |tx| tx.sent);
    let _ = std::fs::remove_file(wav);
    Heard { latency_ms, correlation, stats, frames_sent }
}

#[test]
fn an_espeak_sentence_said_by_vive_is_heard_by_phantom_through_the_server_within_150_ms() {
    let h = talk_over(None, "clean");
    println!(
        "no loss: latency {:.1} ms, envelope correlation {:.3}, {} frames sent, {:?}",
        h.latency_ms, h.correlation, h.frames_sent, h.stats
    );
    assert!(h.correlation >= 0.8, "what Phantom heard follows what Vive said: r = {:.3}", h.correlation);
    assert!(h.latency_ms <= 150.0, "mouth to ear {:.1} ms", h.latency_ms);
    assert!(h.stats.played as u64 + 2 >= h.frames_sent, "every frame played: {:?} of {}", h.stats, h.frames_sent);
    assert_eq!(h.stats.transmissions, 1);
}

/// Which frames a seed's loss hits decides how much of the sentence survives (a lost syllable's onset
/// costs more than a pause), so one seed says little: over six, the median follows what was said as
/// closely as the clean test asks, and none loses the sentence.
#[test]
fn the_sentence_survives_ten_percent_packet_loss() {
    // 5.13 % each way, up to the server and down to Phantom: 10 % of the voice frames end to end.
    let each_way = 1.0 - 0.9f64.sqrt();
    let lossy = Conditions { latency: Duration::ZERO, jitter: Duration::ZERO, loss: each_way };
    let mut correlations = Vec::new();
    for seed in [11, 1, 2, 4, 6, 8] {
        let h = talk_over(Some((lossy, seed)), &format!("lossy-{seed}"));
        println!(
            "10 % loss, seed {seed}: latency {:.1} ms, envelope correlation {:.3}, {} frames sent, {:?}",
            h.latency_ms, h.correlation, h.frames_sent, h.stats
        );
        assert!(
            h.stats.recovered + h.stats.concealed > 0,
            "seed {seed}: frames were lost and filled in: {:?}",
            h.stats
        );
        assert!(h.latency_ms <= 150.0, "seed {seed}: mouth to ear {:.1} ms", h.latency_ms);
        assert!(h.correlation >= 0.5, "seed {seed}: the sentence is lost: r = {:.3}", h.correlation);
        correlations.push(h.correlation);
    }
    correlations.sort_by(f32::total_cmp);
    let median = correlations[correlations.len() / 2 - 1];
    assert!(median >= 0.8, "the lower median r = {median:.3} of {correlations:?}");
}
