//! The Phantom client's Bevy app as the commands run it: headless or with the spectator window, on the
//! network or practising offline, with what ends it (a practice over, a result, the connection gone).

use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use heist_client::ClientNetPlugin;
use heist_shared::protocol::{Phase, SessionView, TICK_HZ};

use crate::client::{PhantomSettings, Workbench};

/// The Phantom client's Bevy app, not yet connected: headless (60 Hz loop) or with the spectator window;
/// on the network, or practising offline.
pub fn app(
    settings: PhantomSettings,
    headless: bool,
    practice: Option<crate::practice::Practice>,
    voices: Option<(crate::audio::AudioEngine, crate::speech::Speaker)>,
) -> Result<App, crate::ClientError> {
    let mut app = App::new();
    if headless {
        app.add_plugins(MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(1.0 / TICK_HZ))))
            .add_plugins(quiet_log());
    } else {
        #[cfg(feature = "spectator")]
        crate::spectator::add_window_plugins(&mut app);
        #[cfg(not(feature = "spectator"))]
        return Err(crate::ClientError::Device("built without the spectator window: run with --headless".into()));
    }
    let practising = practice.is_some();
    match practice {
        None => app.add_plugins(ClientNetPlugin),
        Some(p) => app.insert_resource(p).add_plugins(crate::practice::PracticePlugin),
    };
    let bot = settings.bot;
    let voice = settings.voice.clone();
    match voices {
        Some((audio, speaker)) => crate::client::start_with(&mut app, settings, audio, speaker)?,
        None => crate::client::start(&mut app, settings)?,
    }
    app.add_plugins(heist_client::signals::SignalsPlugin);
    if !practising {
        app.insert_resource(voice).add_plugins((heist_voice::VoicePlugin, crate::walkie::WalkiePlugin));
    }
    if headless && !bot {
        app.add_plugins(crate::terminal::TerminalKeysPlugin);
    }
    #[cfg(feature = "spectator")]
    if !headless {
        app.add_plugins(crate::spectator::SpectatorPlugin);
    }
    if practising {
        app.add_systems(Update, quit_when_practice_is_over);
    } else {
        app.add_systems(Update, (leave_after_a_result, tell_the_link, quit_after_the_link));
    }
    Ok(app)
}

/// The log of `--headless` play: the terminal is the screen reader's, so stdout carries only what is
/// spoken, and the log (stderr) only warnings and errors unless `RUST_LOG` asks for more; no colour codes
/// when stderr is not a terminal.
fn quiet_log() -> bevy::log::LogPlugin {
    bevy::log::LogPlugin {
        level: bevy::log::Level::WARN,
        // netcode logs an error each time the server closes the connection, which the client says itself.
        filter: format!("{},renetcode=off", bevy::log::DEFAULT_FILTER),
        fmt_layer: |_| {
            use std::io::IsTerminal as _;
            let layer = bevy::log::tracing_subscriber::fmt::Layer::default()
                .with_writer(std::io::stderr)
                .with_ansi(std::io::stderr().is_terminal());
            Some(Box::new(layer))
        },
        ..default()
    }
}

/// Says how the practice went once the last verdict's answer was said, and quits a few seconds later.
fn quit_when_practice_is_over(
    p: Res<crate::practice::Practice>,
    time: Res<Time<Real>>,
    mut done_at: Local<Option<f32>>,
    mut told: Local<bool>,
    mut speaker: NonSendMut<crate::speech::Speaker>,
    mut exit: MessageWriter<AppExit>,
) {
    let now = time.elapsed_secs();
    if p.finished() && done_at.is_none() {
        *done_at = Some(now);
    }
    if done_at.is_some_and(|t| now - t > 0.5) && !*told {
        *told = true;
        speaker.say(format!("Practice over: {} right, {} wrong.", p.right, p.wrong));
    }
    if done_at.is_some_and(|t| now - t > 4.5) {
        exit.write(AppExit::Success);
    }
}

/// After a result a player stays for another round (Enter) or leaves (Q); the bot leaves a few seconds
/// after the result is heard.
fn leave_after_a_result(
    q: Query<&SessionView>,
    time: Res<Time<Real>>,
    mut over_at: Local<Option<f32>>,
    state: Res<Workbench>,
    settings: Res<crate::PhantomSettings>,
    mut leaving: ResMut<heist_client::Leaving>,
) {
    let now = time.elapsed_secs();
    let over = q.iter().next().is_some_and(|s| matches!(s.phase, Phase::Won | Phase::Lost(_)));
    if !over {
        *over_at = None;
    } else if over_at.is_none() {
        *over_at = Some(now);
        log::info!("the round is over after {} verdicts", state.verdicts.len());
    }
    if settings.bot && over_at.is_some_and(|t| now - t > 4.0) {
        leaving.start(time.elapsed_secs_f64());
    }
}

/// Says why the server let us go, or that it went silent (3 s without a packet), came back or is gone,
/// and that the client tries to get back in or gave up; earcons go with the words: lost (and given up)
/// low, back rising.
fn tell_the_link(
    link: Res<heist_client::Link>,
    inbox: Res<heist_client::Inbox>,
    reconnect: Res<heist_client::Reconnect>,
    leaving: Res<heist_client::Leaving>,
    mut heard: Local<LinkHeard>,
    mut speaker: NonSendMut<crate::speech::Speaker>,
    mut audio: NonSendMut<crate::audio::AudioEngine>,
) {
    use crate::audio::synth::Earcon;
    use heist_client::Link;
    let lines = heard.news.news(*link, &inbox, &leaving, &reconnect);
    let gave_up = matches!(*reconnect, heist_client::Reconnect::GaveUp(_));
    match (heard.link, *link) {
        (Link::Up, Link::Silent | Link::Gone) if leaving.since.is_none() => audio.earcon(Earcon::LinkDown),
        (Link::Silent, Link::Up) => audio.earcon(Earcon::LinkUp),
        _ if gave_up && !heard.gave_up => audio.earcon(Earcon::LinkDown),
        _ => {}
    }
    heard.link = *link;
    heard.gave_up = gave_up;
    for line in lines {
        speaker.say(line);
    }
}

/// The link as last heard: what was said of it, its state, and whether reconnecting had given up.
#[derive(Default)]
struct LinkHeard {
    news: heist_client::notice::LinkNews,
    link: heist_client::Link,
    gave_up: bool,
}

/// Quits 3 s after the connection ended for good, so the last line is heard.
fn quit_after_the_link(
    link: Res<heist_client::Link>,
    inbox: Res<heist_client::Inbox>,
    reconnect: Res<heist_client::Reconnect>,
    time: Res<Time<Real>>,
    mut ended_at: Local<Option<f32>>,
    mut exit: MessageWriter<AppExit>,
) {
    let now = time.elapsed_secs();
    if heist_client::connection_over(*link, &inbox, &reconnect) {
        ended_at.get_or_insert(now);
    }
    if ended_at.is_some_and(|t| now - t > 3.0) {
        exit.write(AppExit::Success);
    }
}
