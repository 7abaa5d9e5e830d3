//! A blind player needs no sighted help: hosting (the code is spoken, and the recording decodes back to
//! it), joining by spoken prompts and typed answers, every failure before the session spoken with what
//! to do next, the settings menu, the walkie-talkie and a rematch — all through the terminal as a
//! screen-reader user drives it (docs/phantom-client.md, "A blind player's walkthrough").

use std::io::Write;
use std::time::{Duration, Instant};

use heist_shared::protocol::Role;

mod common;
mod listen;
use common::{headless_with_cache, hear, host_with_a_vive_bot, wait};
#[path = "../../haptico/tests/support/haply_service.rs"]
mod haply_service;

/// Everything a finished client wrote on stderr.
fn stderr_of(child: &mut std::process::Child) -> String {
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = std::io::Read::read_to_string(&mut e, &mut err);
    }
    err
}

/// A fresh directory for one test's seat cache and settings.
fn home(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("phantom-blind-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a temp dir");
    dir
}

fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0").expect("a free port").local_addr().expect("addr").port()
}

fn sigterm(child: &std::process::Child) {
    // SAFETY: kill() sends a signal to the child's pid; nothing else is touched.
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
    }
}

/// The NATO words and digit names the code is spelled with, and "then" for its dashes.
fn code_words() -> Vec<&'static str> {
    let mut w = vec![
        "alfa", "bravo", "charlie", "delta", "echo", "foxtrot", "golf", "hotel", "india", "juliett", "kilo", "lima",
        "mike", "november", "oscar", "papa", "quebec", "romeo", "sierra", "tango", "uniform", "victor", "whiskey",
        "x-ray", "yankee", "zulu",
    ];
    w.extend(["zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "then"]);
    w
}

/// The code a run of recognized words spells ("kilo, seven, then, …" → "K7-…").
fn unspell(words: &[String]) -> String {
    words
        .iter()
        .map(|w| match w.as_str() {
            "then" => '-',
            "zero" => '0',
            "one" => '1',
            "two" => '2',
            "three" => '3',
            "four" => '4',
            "five" => '5',
            "six" => '6',
            "seven" => '7',
            "eight" => '8',
            "nine" => '9',
            nato => nato.chars().next().map_or('?', |c| c.to_ascii_uppercase()),
        })
        .collect()
}

/// The longest run of recognized code words in `words`, spelled back into a code.
fn longest_code(words: &[Option<String>]) -> String {
    let mut best: Vec<String> = Vec::new();
    let mut run: Vec<String> = Vec::new();
    for w in words.iter().chain([None].iter()) {
        match w {
            Some(w) => run.push(w.clone()),
            None => {
                if run.len() > best.len() {
                    best = std::mem::take(&mut run);
                }
                run.clear();
            }
        }
    }
    unspell(&best)
}

#[test]
fn the_recognizer_hears_every_letter_and_digit_of_a_spelled_code_and_not_the_sentence_around_it() {
    // Checked on its own so a failure of the hosting test below is the client's, not the recognizer's.
    // The hosting test's code is random: these three cover every letter and digit a code can hold
    // (server/src/net/tokens: no 0, 1, I or O), so a word the recognizer cannot hear fails here, every time.
    let vocabulary = listen::Vocabulary::new(&code_words(), client_haptic::client::SPELLING_WPM);
    for code in ["ABCD-EFGH-JKLM", "NPQR-STUV-WXYZ", "2345-6789-QX7M"] {
        let line = format!("The code, spelled: {}. R repeats it.", client_haptic::prompt::spell(code));
        let said = listen::espeak(&line, client_haptic::client::SPELLING_WPM);
        let words = vocabulary.transcribe(&said);
        for (s, e) in listen::utterances(&said) {
            println!("{:.2}-{:.2} s: {:?}", s as f32 / 48_000.0, e as f32 / 48_000.0, vocabulary.scores(&said[s..e]));
        }
        println!("heard: {words:?}");
        assert_eq!(longest_code(&words), code);
    }
}

#[test]
fn hosting_speaks_the_join_code_and_the_recording_decodes_back_to_the_printed_code() {
    let dir = home("host-speech");
    let wav = dir.join("heard.wav");
    let bind = format!("127.0.0.1:{}", free_port());
    // The lines before the code are said fast; the spelling is said at 120 words a minute whatever the rate.
    let args = ["host", "--bind", &bind, "--speech-rate", "300", "--wav", wav.to_str().expect("utf-8")];
    let (mut child, _stdin, rx) = headless_with_cache(&args, &dir);
    let mut lines = Vec::new();
    assert!(hear(&rx, &mut lines, "The code, spelled:", Duration::from_secs(60)), "{lines:#?}");
    let printed = lines
        .iter()
        .find_map(|l| l.split("with the code ").nth(1))
        .expect("the code is printed on one line")
        .trim_end_matches('.')
        .to_owned();
    // Everything is queued at once: the welcome, the menu's first item and where to join (about ten
    // seconds at 300 words a minute), then the spelled code (about twelve at 120). Then the player is
    // stopped from outside (SIGTERM), and the recording must still be whole.
    std::thread::sleep(Duration::from_secs(40));
    sigterm(&child);
    let status = wait(&mut child, Duration::from_secs(15));
    assert!(status.is_some(), "SIGTERM ended the client");
    let heard = heist_voice::mic::read_wav(&wav).expect("the recording was written whole");
    assert!(heard.len() > 48_000 * 39, "{} s recorded", heard.len() / 48_000);

    let vocabulary = listen::Vocabulary::new(&code_words(), client_haptic::client::SPELLING_WPM);
    let words = vocabulary.transcribe(&heard);
    for (s, e) in listen::utterances(&heard) {
        println!("{:.2}-{:.2} s: {:?}", s as f32 / 48_000.0, e as f32 / 48_000.0, vocabulary.scores(&heard[s..e]));
    }
    println!("heard: {words:?}");
    // The longest run of recognized code words is the spelled code.
    assert_eq!(longest_code(&words), printed, "the spoken words decode back to the printed code");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn joining_by_spoken_prompts_asks_again_after_each_mistake_until_the_player_is_in() {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (addr, code, host) = host_with_a_vive_bot(stop.clone(), Default::default(), 300.0);
    let dir = home("join-prompts");
    let (mut child, mut stdin, rx) = headless_with_cache(&["join"], &dir);
    let mut lines = Vec::new();
    let t = Duration::from_secs(20);
    let mut wrong = code.clone();
    let last = wrong.pop().expect("a code");
    wrong.push(if last == 'A' { 'B' } else { 'A' });
    assert!(hear(&rx, &mut lines, "Which server?", t), "{lines:#?}");
    // Nobody listens on port 1; the typo is deleted with a backspace.
    writeln!(stdin, "127.0.0.1:1x\x7f").expect("types");
    assert!(hear(&rx, &mut lines, "Server 127.0.0.1:1.", t), "the answer is said back: {lines:#?}");
    assert!(hear(&rx, &mut lines, "The join code?", t), "{lines:#?}");
    writeln!(stdin, "{}", wrong.to_lowercase()).expect("types a wrong code, in lower case");
    assert!(hear(&rx, &mut lines, "Nobody answers at 127.0.0.1:1.", t), "{lines:#?}");
    assert!(hear(&rx, &mut lines, "Which server?", t), "the address is asked again: {lines:#?}");
    writeln!(stdin, "{addr}").expect("types");
    // The code typed before is tried at the new address: the host says it is wrong.
    assert!(hear(&rx, &mut lines, "The host says that code is wrong.", t), "{lines:#?}");
    assert!(hear(&rx, &mut lines, "The join code?", t), "{lines:#?}");
    writeln!(stdin, "not a code").expect("types");
    assert!(hear(&rx, &mut lines, "That is not a join code:", t), "{lines:#?}");
    writeln!(stdin, "{code}").expect("types");
    assert!(hear(&rx, &mut lines, "Welcome to Phantom Heist.", t), "in: {lines:#?}");
    assert!(hear(&rx, &mut lines, "Vive joined.", t), "{lines:#?}");
    writeln!(stdin, "q").expect("types q");
    assert!(hear(&rx, &mut lines, "Leaving the session.", t), "{lines:#?}");
    let status = wait(&mut child, Duration::from_secs(10));
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = host.join();
    assert!(status.is_some_and(|s| s.success()), "{status:?}: {lines:#?}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn every_failure_before_the_session_is_spoken_with_what_to_do_next() {
    let dir = home("failures");
    let wav = dir.join("failure.wav");
    let run = |args: &[&str]| {
        let (mut child, _stdin, rx) = headless_with_cache(args, &dir);
        let status = wait(&mut child, Duration::from_secs(60)).expect("ends by itself");
        let err = stderr_of(&mut child);
        (status, rx.try_iter().collect::<Vec<String>>(), err)
    };
    // Nobody at the address.
    let (status, said, err) =
        run(&["join", "127.0.0.1:1", "--code", "ABCD-EFGH-JKLM", "--wav", wav.to_str().expect("utf-8")]);
    assert!(!status.success());
    assert!(said.iter().any(|l| l.starts_with("Nobody answers at 127.0.0.1:1. Check the address")), "{said:#?}");
    assert_eq!(err.lines().count(), 1, "one line on stderr: {err}");
    // It was said aloud, not only printed: a second and more of speech in the recording.
    let heard = heist_voice::mic::read_wav(&wav).expect("the recording");
    let loud = heard.iter().filter(|s| s.abs() > 0.02).count();
    assert!(loud > 48_000, "{loud} loud samples");

    // A device that is not there: said before anything else (the address is never tried), within seconds.
    let closed = free_port();
    let haply = format!("haply:ws://127.0.0.1:{closed}/");
    let args = ["join", "127.0.0.1:1", "--code", "ABCD-EFGH-JKLM", "--device", &haply];
    let (mut child, _stdin, rx) = headless_with_cache(&args, &dir);
    let mut said = Vec::new();
    let not_ready = "The haptic device is not ready: the Haply Inverse3: no Haply Inverse Service at ws://127.0.0.1:";
    assert!(hear(&rx, &mut said, not_ready, Duration::from_secs(5)), "said within 5 s: {said:#?}");
    assert!(said.last().is_some_and(|l| l.contains("start the service")), "{said:#?}");
    let status = wait(&mut child, Duration::from_secs(60)).expect("ends once it is said");
    said.extend(rx.try_iter());
    assert!(!status.success());
    assert!(!said.iter().any(|l| l.starts_with("Nobody answers")), "the device comes first: {said:#?}");
    let err = stderr_of(&mut child);
    assert_eq!(err.lines().count(), 1, "one line on stderr: {err}");
    let (status, said, err) = run(&["join", "127.0.0.1:1", "--code", "ABCD-EFGH-JKLM", "--device", "falcon"]);
    assert!(!status.success());
    assert!(said.iter().any(|l| l.starts_with("The haptic device is not ready: no Novint Falcon")), "{said:#?}");
    assert_eq!(err.lines().count(), 1, "one line on stderr: {err}");
    // Practising with it is looked for the same way.
    let (status, said, err) = run(&["practice", "--kind", "crown", "--device", "falcon"]);
    assert!(!status.success());
    assert!(said.iter().any(|l| l.starts_with("The haptic device is not ready: no Novint Falcon")), "{said:#?}");
    assert_eq!(err.lines().count(), 1, "one line on stderr: {err}");

    // A wrong code, given on the command line: said, and the program ends (nothing to ask again).
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (addr, code, host) = host_with_a_vive_bot(stop.clone(), Default::default(), 300.0);
    let wrong = format!("{}-ZZZZ-ZZZZ", code.split('-').next().expect("a room"));
    let (status, said, _) = run(&["join", &addr.to_string(), "--code", &wrong]);
    assert!(!status.success());
    assert!(said.iter().any(|l| l == "The host says that code is wrong. Check it with your partner."), "{said:#?}");
    // Hosting on a port that is taken.
    let (status, said, err) = run(&["host", "--bind", &addr.to_string()]);
    assert!(!status.success(), "{err}");
    assert!(said.iter().any(|l| l.starts_with("Could not host the heist:") && l.contains("--bind")), "{said:#?}");
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = host.join();
    let _ = std::fs::remove_dir_all(dir);
}

/// The Inverse3 through a local stand-in for the Haply Inverse Service (no hardware): the practice
/// drives it, and when the service goes away mid-practice the player hears it once, no force goes out
/// after, and the client goes on until the player quits.
#[test]
fn a_haply_service_that_goes_away_mid_practice_is_said_once_and_the_client_quits_cleanly() {
    use haply_service::{FakeService, Script};
    let dir = home("haply");
    let service = FakeService::start(Script { inverse3: true, close_after: None, wander: false });
    let device = format!("haply:{}", service.url());
    let args = ["practice", "--kind", "crown", "--seed", "3", "--device", &device];
    let (mut child, mut stdin, rx) = headless_with_cache(&args, &dir);
    let mut said = Vec::new();
    // The device is looked for and the player told what to do before the practice starts.
    let found = "Found the Haply Inverse3. Hold its grip still where you want to play";
    assert!(hear(&rx, &mut said, found, Duration::from_secs(10)), "{said:#?}");
    assert!(hear(&rx, &mut said, "You can feel it now.", Duration::from_secs(120)), "{said:#?}");
    // The haptic loop commands the device through the service: hundreds of forces a second.
    let start = Instant::now();
    while service.seen.lock().expect("seen").commands < 500 {
        assert!(start.elapsed() < Duration::from_secs(10), "forces reach the service: {said:#?}");
        std::thread::sleep(Duration::from_millis(10));
    }
    let seen = service.seen.clone();
    drop(service); // the service stops: every connection closes
    let sent = seen.lock().expect("seen").commands;
    let lost = "The Haply service went away: no force reaches the Inverse3.";
    assert!(hear(&rx, &mut said, lost, Duration::from_secs(10)), "said within 10 s: {said:#?}");
    // Still running, and listening: the player quits.
    std::thread::sleep(Duration::from_millis(500));
    assert!(child.try_wait().expect("polls").is_none(), "the client goes on without its device: {said:#?}");
    writeln!(stdin, "q").expect("types");
    let status = wait(&mut child, Duration::from_secs(60)).expect("ends when told");
    said.extend(rx.try_iter());
    let err = stderr_of(&mut child);
    assert!(status.success(), "exited with {status}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(said.iter().filter(|l| l.starts_with(lost)).count(), 1, "said once: {said:#?}");
    assert_eq!(seen.lock().expect("seen").commands, sent, "no force is read after the service went away");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_settings_menu_is_spoken_a_change_is_heard_and_saved_and_a_bad_file_falls_back_with_a_warning() {
    let dir = home("settings");
    let file = dir.join("config").join("phantom-heist").join("settings.toml");
    let (mut child, mut stdin, rx) = headless_with_cache(&["practice", "--kind", "idol"], &dir);
    let mut lines = Vec::new();
    let t = Duration::from_secs(20);
    assert!(hear(&rx, &mut lines, "Welcome to Phantom Heist.", t), "{lines:#?}");
    writeln!(stdin, "o").expect("types o");
    assert!(hear(&rx, &mut lines, "Settings. Up and down choose a setting", t), "{lines:#?}");
    assert!(hear(&rx, &mut lines, "Speech rate, 175 words a minute.", t), "{lines:#?}");
    writeln!(stdin, "right").expect("types");
    assert!(hear(&rx, &mut lines, "Speech rate, 200 words a minute.", t), "{lines:#?}");
    for line in ["down", "down", "left", "left"] {
        writeln!(stdin, "{line}").expect("types");
    }
    assert!(hear(&rx, &mut lines, "Sound volume, 80 percent.", t), "{lines:#?}");
    writeln!(stdin).expect("types Enter: close");
    assert!(hear(&rx, &mut lines, "Settings saved. Back to the game.", t), "{lines:#?}");
    writeln!(stdin, "q").expect("types q");
    let _ = wait(&mut child, Duration::from_secs(10));
    let saved = std::fs::read_to_string(&file).expect("the file was written");
    assert!(saved.contains("speech_rate = 200") && saved.contains("sound_volume = 80"), "{saved}");

    // Started again: the saved settings are in force. Then the file is broken by hand.
    std::fs::write(&file, "speech_rate = \"fast\"\n").expect("writes");
    let (mut child, mut stdin, rx) = headless_with_cache(&["practice", "--kind", "idol"], &dir);
    let mut lines = Vec::new();
    assert!(hear(&rx, &mut lines, "The settings file", t), "{lines:#?}");
    let warning = lines.last().expect("a line").clone();
    assert!(warning.contains("line 1") && warning.ends_with("using the defaults."), "{warning}");
    assert!(hear(&rx, &mut lines, "Welcome to Phantom Heist.", t), "the client carries on: {lines:#?}");
    writeln!(stdin, "o").expect("types o");
    assert!(hear(&rx, &mut lines, "Speech rate, 175 words a minute.", t), "the defaults: {lines:#?}");
    writeln!(stdin, "q").expect("types");
    writeln!(stdin, "q").expect("types");
    let _ = wait(&mut child, Duration::from_secs(10));
    let _ = std::fs::remove_dir_all(dir);
}

/// What the partner's client heard of Phantom's walkie-talkie.
#[derive(bevy::prelude::Resource, Default)]
struct PartnerHeard(usize);

fn count_voice(
    mut frames: bevy::prelude::MessageReader<heist_shared::protocol::PartnerVoice>,
    mut heard: bevy::prelude::ResMut<PartnerHeard>,
) {
    heard.0 += frames.read().count();
}

#[test]
fn a_blind_players_walkthrough_host_share_the_code_talk_warn_change_a_setting_play_and_play_again() {
    use bevy::prelude::*;
    let dir = home("walkthrough");
    let mic = dir.join("phantom-says.wav");
    let ok = std::process::Command::new("espeak-ng").arg("-w").arg(&mic).arg("Vive, the east door.").status();
    assert!(ok.is_ok_and(|s| s.success()), "espeak-ng writes the microphone's file");
    let bind = format!("127.0.0.1:{}", free_port());
    let args = ["host", "--bind", &bind, "--time-limit", "6", "--mic-wav", mic.to_str().expect("utf-8")];
    let (mut child, mut stdin, rx) = headless_with_cache(&args, &dir);
    let mut lines = Vec::new();
    let t = Duration::from_secs(30);
    assert!(hear(&rx, &mut lines, "You host the heist.", t), "{lines:#?}");
    let code = lines.last().and_then(|l| l.split("with the code ").nth(1)).expect("a code").trim_end_matches('.');
    // The partner (an idle Vive bot for two rounds) joins with the code as heard.
    let token = heist_client::request_token(bind.parse().expect("addr"), code, Role::Vive, Duration::from_secs(5))
        .expect("the code admits the partner");
    let mut vive = heist_server::demo::stepped_client_app();
    vive.add_plugins(heist_bots::ViveBotPlugin { style: heist_bots::ViveStyle::Idle })
        .insert_resource(heist_bots::Rounds(2))
        .init_resource::<PartnerHeard>()
        .add_systems(PreUpdate, count_voice);
    vive.finish();
    vive.cleanup();
    heist_client::connect(&mut vive, token).expect("connects");
    // Everything below is typed as lines; the partner's client runs at 60 Hz meanwhile.
    let script: Vec<(&str, Option<&str>)> = vec![
        ("Vive joined.", Some("talk")),
        ("Talking to Vive.", None),
        ("Over.", None),
        ("Settings. Up and down", None),
        ("Speech rate, 200 words a minute.", Some("")),
        ("Settings saved.", Some("")),
        ("Ready. Waiting for Vive.", None),
        ("The heist has begun.", Some("h")),
        ("You told Vive to hide.", None),
        ("Vive has your warning to hide.", None),
        ("Time is up. The heist is lost.", None),
        ("Enter asks for another round", Some("again")),
        ("Round 2 begins", None),
        ("Time is up. The heist is lost.", None),
        ("Enter asks for another round", Some("q")),
        ("Leaving the session.", None),
    ];
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut step = 0;
    let mut talking_since: Option<Instant> = None;
    while step < script.len() {
        assert!(Instant::now() < deadline, "stuck waiting for {:?}; heard {lines:#?}", script[step].0);
        vive.update();
        std::thread::sleep(Duration::from_millis(16));
        // Over after two seconds of talk; then the settings: one step faster.
        if talking_since.is_some_and(|s| s.elapsed() > Duration::from_secs(2)) {
            talking_since = None;
            writeln!(stdin, "over").expect("types");
        }
        while let Ok(line) = rx.try_recv() {
            let (expect, then) = script[step.min(script.len() - 1)];
            if step < script.len() && line.starts_with(expect) {
                if let Some(typed) = then {
                    writeln!(stdin, "{typed}").expect("types");
                }
                if expect == "Talking to Vive." {
                    talking_since = Some(Instant::now());
                }
                if expect == "Over." {
                    writeln!(stdin, "o").expect("types");
                    writeln!(stdin, "right").expect("types");
                }
                step += 1;
            }
            lines.push(line);
        }
    }
    let status = wait(&mut child, Duration::from_secs(10));
    println!("Phantom heard:\n{}", lines.join("\n"));
    assert!(status.is_some_and(|s| s.success()), "{status:?}");
    let frames = vive.world().resource::<PartnerHeard>().0;
    assert!(frames >= 50, "Vive's client got Phantom's two seconds of voice: {frames} frames");
    let saved = std::fs::read_to_string(dir.join("config/phantom-heist/settings.toml")).expect("saved");
    assert!(saved.contains("speech_rate = 200"), "{saved}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_partner_joining_dropping_and_coming_back_is_heard_in_that_order() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let (stop, away) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
    let (tx, rx_code) = std::sync::mpsc::channel();
    let (host_stop, vive_away) = (stop.clone(), away.clone());
    // A host with an idle Vive bot that holds its seat: while `away` is set its client stands still
    // (a frozen laptop); afterwards its client notices the silence and takes the seat back by itself.
    let host = std::thread::spawn(move || {
        let mut server = heist_server::build_server(heist_server::ServerOptions::local_test(9)).expect("server");
        let endpoint = server.tokens.as_ref().expect("secure").addr;
        tx.send((endpoint, server.join_code().expect("a code").code)).expect("the test waits");
        let mut vive: Option<bevy::app::App> = None;
        let deadline = Instant::now() + Duration::from_secs(120);
        while !host_stop.load(Ordering::Relaxed) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(16));
            server.update();
            if vive.is_none() && server.game().is_present(Role::Phantom) {
                let token = heist_server::demo::token(&server, Role::Vive).expect("a token");
                let mut app = heist_server::demo::stepped_client_app();
                app.add_plugins(heist_bots::ViveBotPlugin { style: heist_bots::ViveStyle::Idle });
                app.finish();
                app.cleanup();
                heist_client::connect(&mut app, token).expect("connects");
                heist_client::hold_seat(&mut app, None, endpoint, Role::Vive);
                vive = Some(app);
            }
            if let Some(v) = vive.as_mut().filter(|_| !vive_away.load(Ordering::Relaxed)) {
                v.update();
            }
        }
        server.log().to_vec()
    });
    let (addr, code) = rx_code.recv_timeout(Duration::from_secs(30)).expect("the host starts");
    let dir = home("partner-notices");
    let (mut child, mut stdin, rx) = headless_with_cache(&["join", &addr.to_string(), "--code", &code], &dir);
    let mut lines = Vec::new();
    let t = Duration::from_secs(30);
    assert!(hear(&rx, &mut lines, "Vive joined.", t), "{lines:#?}");
    away.store(true, Ordering::Relaxed);
    assert!(hear(&rx, &mut lines, "Vive's connection dropped.", t), "{lines:#?}");
    away.store(false, Ordering::Relaxed);
    assert!(hear(&rx, &mut lines, "Vive is back.", t), "{lines:#?}");
    writeln!(stdin, "q").expect("types q");
    let status = wait(&mut child, Duration::from_secs(10));
    stop.store(true, Ordering::Relaxed);
    let log = host.join().expect("the host thread");
    assert!(status.is_some_and(|s| s.success()), "{status:?}");
    let at = |text: &str| lines.iter().position(|l| l.starts_with(text));
    assert!(
        at("Vive joined.") < at("Vive's connection dropped.") && at("Vive's connection dropped.") < at("Vive is back.")
    );
    assert!(log.iter().any(|l| l.contains("Vive is back")), "{log:#?}");
    let _ = std::fs::remove_dir_all(dir);
}
