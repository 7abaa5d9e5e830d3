//! End to end: the real server, the careful Vive bot and this client in bot mode (real haptic loop on
//! the sim device, real collision, real force, judging by touch) play a whole heist over loopback UDP.
//!
//! The clock is stepped by hand (1/60 s per update) so the sneaking runs fast, but while Phantom has a
//! copy to feel the steps keep to wall-clock time: the exploration takes as long in the game as it does
//! on the haptic device.

use std::time::{Duration, Instant};

use bevy::prelude::*;
use client_haptic::audio::{AudioOutput, AudioSettings};
use client_haptic::bench::LoopRates;
use client_haptic::{PhantomSettings, Workbench};
use heist_bots::{ViveBotPlugin, ViveStyle};
use heist_server::demo::join;
use heist_server::{ServerOptions, build_server};
use heist_shared::protocol::{Phase, Role, TICK_HZ};

/// An easy seed the careful Vive bot wins with a Phantom that takes its time (see docs/phantom-client.md).
const SEED: u64 = 1;

#[test]
fn the_server_a_vive_bot_and_the_touch_bot_win_a_heist_over_loopback_udp() {
    let wav = std::env::temp_dir().join(format!("phantom-e2e-{}.wav", std::process::id()));
    let mut options = ServerOptions::local_test(SEED);
    options.game.difficulty = heist_shared::rules::Difficulty::Easy;
    let limit = options.level.time_limit_s * options.level.tuning(options.game.difficulty).time_scale;
    let mut server = build_server(options).expect("server starts");
    let mut vive = join(&server, Role::Vive, |app| {
        app.add_plugins(ViveBotPlugin { style: ViveStyle::Careful });
    })
    .expect("Vive joins");
    let settings = PhantomSettings {
        bot: true,
        audio: AudioSettings { output: AudioOutput::Background(Some(wav.clone())), ..Default::default() },
        ..Default::default()
    };
    let mut phantom =
        join(&server, Role::Phantom, |app| client_haptic::start(app, settings).expect("Phantom's client starts"))
            .expect("Phantom joins");

    let tick = Duration::from_secs_f64(1.0 / TICK_HZ);
    let mut paced_since: Option<(Instant, u64)> = None;
    let max_ticks = ((limit as f64 + 60.0) * TICK_HZ) as u64;
    let mut paced_ticks = 0;
    let started = Instant::now();
    for t in 0..max_ticks {
        server.update();
        vive.update();
        phantom.update();
        if !server.game().is_running() && server.game().phase != Phase::Lobby {
            for _ in 0..30 {
                server.update();
                vive.update();
                phantom.update();
            }
            break;
        }
        // Keep to wall-clock time while Phantom feels a copy.
        if phantom.world().resource::<Workbench>().busy() {
            let (since, t0) = *paced_since.get_or_insert((Instant::now(), t));
            let due = since + tick * (t - t0 + 1) as u32;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            paced_ticks += 1;
        } else {
            paced_since = None;
        }
        assert!(started.elapsed() < Duration::from_secs(1500), "the heist took too long in wall-clock time");
    }
    let game = server.game();
    let state = phantom.world().resource::<Workbench>();
    println!(
        "heist over after {:.0} s of game time ({:.0} s felt in real time), {:.0} s wall clock: {:?}",
        game.elapsed_s,
        paced_ticks as f64 / TICK_HZ,
        started.elapsed().as_secs_f64(),
        game.phase
    );
    for v in &state.verdicts {
        println!(
            "verdict on copy {}: {} ({:?})",
            v.item.0,
            if v.real { "real" } else { "fake" },
            v.findings.as_ref().map(|f| f.describe())
        );
    }
    let felt: Vec<_> = phantom.world().resource::<LoopRates>().rates.iter().filter(|w| w.with_copy).collect();
    let min = |f: fn(&&client_haptic::haptics::RateWindow) -> u32| felt.iter().map(f).min().unwrap_or(0);
    println!(
        "haptic loop while a copy was on the bench: {} one-second windows, haptic min {} Hz, collision min {} Hz",
        felt.len(),
        min(|w| w.haptic_hz),
        min(|w| w.collision_hz)
    );
    assert_eq!(
        game.phase,
        Phase::Won,
        "the heist should be won; log: {:?}",
        &server.log()[server.log().len().saturating_sub(15)..]
    );
    assert!(state.verdicts.iter().any(|v| v.findings.is_some()), "verdicts come from touch");
    assert!(!felt.is_empty(), "the haptic loop ran while copies were felt");
    // Both loops kept their 1 kHz while copies were felt: the median one-second window within 10 % (a
    // window or two may be short on this shared machine; a loop that slowed down or stopped is not).
    let median = |f: fn(&&client_haptic::haptics::RateWindow) -> u32| {
        let mut hz: Vec<u32> = felt.iter().map(f).collect();
        hz.sort_unstable();
        hz[hz.len() / 2]
    };
    let (haptic, collision) = (median(|w| w.haptic_hz), median(|w| w.collision_hz));
    assert!((900..=1100).contains(&haptic), "haptic loop median {haptic} Hz over {} windows", felt.len());
    assert!((900..=1100).contains(&collision), "collision loop median {collision} Hz over {} windows", felt.len());
    drop(phantom);
    let bytes = std::fs::read(&wav).expect("the session's audio was written");
    let loud = bytes[44..].chunks_exact(2).filter(|s| i16::from_le_bytes([s[0], s[1]]).unsigned_abs() > 1000).count();
    assert!(loud > 1000, "the session was heard: {loud} loud samples");
    let _ = std::fs::remove_file(wav);
}
