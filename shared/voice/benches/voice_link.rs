//! The walkie-talkie in wall-clock time over loopback: mouth-to-ear latency and what voice at full rate
//! does to the game's own messages. Prints figures (medians, p90, the ratio with and without voice).
//!
//!     cargo bench -p heist_voice --bench voice_link
//!
//! The server runs on its own thread in real time (as `heist-server host` does); Vive's and Phantom's
//! client cores run in this thread at 60 Hz of wall-clock time; Phantom's audio is rendered as the
//! seconds pass, like a sound card with no buffer of its own (a real card adds its buffer, ~10–20 ms).
//! Mouth-to-ear: when each sample of an espeak-ng sentence was due at Vive's microphone and when it
//! was rendered at Phantom's, aligned by the speech envelope. Game messages: Phantom sends a warning
//! every 1.2 s; the delay until Vive's client holds the server's `Warning` event.

use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use heist_audio::{AudioEngine, AudioOutput, AudioSettings};
use heist_shared::protocol::{ClientMsg, GameEvent, PhantomMsg, Role, WarningKind};
use heist_voice::measure::{envelope, pearson};
use heist_voice::plugin::Voice;
use heist_voice::{MicChoice, TalkMode, VoicePlugin, VoiceSettings};

const RATE: f64 = 48_000.0;

fn sentence(path: &std::path::Path, repeat: usize) -> Vec<f32> {
    let text = "Phantom, the guard by the east door is gone. I am bringing the crown now. ".repeat(repeat);
    let ok = std::process::Command::new("espeak-ng").arg("-w").arg(path).arg(text).status().is_ok_and(|s| s.success());
    assert!(ok, "espeak-ng runs (scripts/deps.sh installs it)");
    heist_voice::mic::read_wav(path).expect("reads")
}

fn client(token: heist_client::ConnectToken, setup: impl FnOnce(&mut App)) -> App {
    let mut app = heist_server::demo::client_with_token(token, setup).expect("joins");
    app.insert_resource(TimeUpdateStrategy::Automatic);
    app
}

struct Run {
    latency_ms: Option<f64>,
    warn_delays_ms: Vec<f64>,
    voice_frames: u64,
}

/// One run of `seconds`: Vive says `wav` (if any) with an open microphone, Phantom warns every 1.2 s.
fn run(wav: Option<&std::path::Path>, said: &[f32], seconds: f64) -> Run {
    let host = heist_server::embedded::HostOptions {
        bind: "127.0.0.1:0".parse().expect("an address"),
        advertise: None,
        seed: Some(3),
        time_limit_s: None,
        difficulty: Default::default(),
    };
    let here = heist_server::embedded::start(host).expect("server");
    let timeout = Duration::from_secs(5);
    let token = |role| heist_client::request_token(here.endpoint, &here.code, role, timeout).expect("token");
    let mic = wav.map_or(MicChoice::Off, |p| MicChoice::Wav(p.to_owned()));
    let mut vive = client(token(Role::Vive), |app| {
        app.insert_resource(VoiceSettings { mic, mode: TalkMode::Open }).add_plugins(VoicePlugin);
    });
    let audio = AudioEngine::new(&AudioSettings { output: AudioOutput::Manual, ..Default::default() }).expect("audio");
    let capture = audio.capture().expect("memory").clone();
    let mut phantom = client(token(Role::Phantom), |app| {
        app.insert_non_send(audio)
            .insert_resource(VoiceSettings { mic: MicChoice::Off, mode: TalkMode::PushToTalk })
            .add_plugins(VoicePlugin);
    });
    let tick = Duration::from_secs_f64(1.0 / 60.0);
    let start = Instant::now();
    let mut heard: Vec<f32> = Vec::new();
    let mut rendered_from: Option<Instant> = None;
    let mut mouth: Option<Instant> = None;
    let mut warn_sent: Option<Instant> = None;
    let mut next_warn = start + Duration::from_secs(2);
    let mut warn_delays_ms = Vec::new();
    let mut seen_events = 0;
    let mut next = start;
    while start.elapsed().as_secs_f64() < seconds {
        next += tick;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let before = Instant::now();
        vive.update();
        if mouth.is_none()
            && vive.world().get_non_send::<Voice>().is_some_and(|v| v.tx.as_ref().is_ok_and(|t| t.is_talking()))
        {
            mouth = Some(before);
        }
        phantom.update();
        let now = Instant::now();
        let from = *rendered_from.get_or_insert(now);
        let due = (now.duration_since(from).as_secs_f64() * RATE) as usize;
        if due > heard.len() {
            heard.extend(capture.render(due - heard.len()).iter().map(|(l, r)| 0.5 * (l + r)));
        }
        if warn_sent.is_none() && now >= next_warn {
            phantom.world_mut().write_message(ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Hide)));
            warn_sent = Some(now);
            next_warn = now + Duration::from_millis(1200);
        }
        let events = &vive.world().resource::<heist_client::Inbox>().events;
        if events.len() > seen_events {
            if let Some(sent) = warn_sent
                && events[seen_events..].iter().any(|e| matches!(e, GameEvent::Warning(_)))
            {
                warn_delays_ms.push(Instant::now().duration_since(sent).as_secs_f64() * 1000.0);
                warn_sent = None;
            }
            seen_events = events.len();
        }
    }
    let voice_frames = vive.world().get_non_send::<Voice>().and_then(|v| v.tx.as_ref().ok().map(|t| t.sent));
    let latency_ms = match (mouth, rendered_from, wav) {
        (Some(mouth), Some(from), Some(_)) => {
            // Envelopes in 2.5 ms windows; the lag where what was heard best follows what was said.
            let hop = 120;
            let (said_env, heard_env) = (envelope(&said[..said.len().min(48_000 * 4)], hop), envelope(&heard, hop));
            // Where the mouth's start falls in what was heard.
            let offset = (mouth.duration_since(from).as_secs_f64() * RATE / hop as f64).floor() as usize;
            let lag = (0..200).filter(|l| heard_env.len() > offset + l + said_env.len()).max_by(|a, b| {
                let c = |l: usize| pearson(&said_env, &heard_env[offset + l..]);
                c(*a).total_cmp(&c(*b))
            });
            lag.map(|l| {
                let mouth_in_stream = mouth.duration_since(from).as_secs_f64();
                ((offset + l) as f64 * hop as f64 / RATE - mouth_in_stream) * 1000.0
            })
        }
        _ => None,
    };
    Run { latency_ms, warn_delays_ms, voice_frames: voice_frames.unwrap_or(0) }
}

fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() { f64::NAN } else { v[((v.len() - 1) as f64 * q).round() as usize] }
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is taken.
    let dir = std::env::temp_dir().join(format!("voice-link-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let short = dir.join("sentence.wav");
    let said = sentence(&short, 1);
    let long = dir.join("talk.wav");
    sentence(&long, 8);

    let mut latencies = Vec::new();
    for i in 0..5 {
        let r = run(Some(&short), &said, said.len() as f64 / RATE + 4.0);
        match r.latency_ms {
            Some(l) => latencies.push(l),
            None => println!("run {i}: no alignment found"),
        }
    }
    println!(
        "mouth to ear (to the renderer), {} runs: median {:.1} ms, min {:.1}, max {:.1}",
        latencies.len(),
        quantile(&latencies, 0.5),
        quantile(&latencies, 0.0),
        quantile(&latencies, 1.0)
    );

    // Side by side, alternating: game messages without voice, then with Vive talking at full rate.
    let (mut quiet, mut talking, mut frames) = (Vec::new(), Vec::new(), 0);
    for _ in 0..2 {
        quiet.extend(run(None, &said, 20.0).warn_delays_ms);
        let r = run(Some(&long), &said, 20.0);
        frames += r.voice_frames;
        talking.extend(r.warn_delays_ms);
    }
    println!(
        "warning to Vive without voice: {} messages, median {:.1} ms, p90 {:.1} ms",
        quiet.len(),
        quantile(&quiet, 0.5),
        quantile(&quiet, 0.9)
    );
    println!(
        "warning to Vive with Vive talking ({frames} voice frames): {} messages, median {:.1} ms, p90 {:.1} ms",
        talking.len(),
        quantile(&talking, 0.5),
        quantile(&talking, 0.9)
    );
    println!("ratio of medians (with / without voice): {:.2}", quantile(&talking, 0.5) / quantile(&quiet, 0.5));
    let _ = std::fs::remove_dir_all(dir);
}
