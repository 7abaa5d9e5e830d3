//! The `client_haptic` command line: `join ADDR --code CODE` and `devices`.
//!
//! You need this module to run the client from a shell; [`app`] builds the same Bevy app the tests
//! drive by hand.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use clap::{Parser, Subcommand, ValueEnum};
use heist_client::ClientNetPlugin;
use heist_shared::protocol::{Phase, Role, SessionView, TICK_HZ};

use crate::audio::{AudioOutput, AudioSettings, SpatialMode};
use crate::client::{PhantomSettings, PhantomState};
use crate::device::DeviceChoice;
use crate::haptics::{HapticsSettings, RenderingChoice};

/// The command line.
#[derive(Parser, Debug)]
#[command(
    name = "client_haptic",
    about = "Phantom Heist: join as Phantom, the blind player, and play by touch and sound"
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Where the sound goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AudioChoice {
    /// The sound card (falls back to memory when there is none).
    Card,
    /// Rendered in memory only (with `--wav`, into that file too).
    Memory,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Join a session as Phantom.
    Join(JoinArgs),
    /// Host a session (the server runs in this client) and join it as Phantom; the join code is spoken.
    Host(crate::host::HostArgs),
    /// Practise at the workbench offline: the copies of one artifact, one after another.
    Practice(PracticeArgs),
    /// List the device presets and the HID devices found.
    Devices,
}

/// The artifact to practise on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// The crown (count its points).
    Crown,
    /// The amphora (count its ridges).
    Amphora,
    /// The idol (count its notches).
    Idol,
}

impl From<KindArg> for heist_shared::artifact::ArtifactKind {
    fn from(kind: KindArg) -> Self {
        match kind {
            KindArg::Crown => Self::Crown,
            KindArg::Amphora => Self::Amphora,
            KindArg::Idol => Self::Idol,
        }
    }
}

/// Arguments of `practice`.
#[derive(clap::Args, Debug, Clone)]
pub struct PracticeArgs {
    /// Which artifact.
    #[arg(long, value_enum, default_value_t = KindArg::Crown)]
    pub kind: KindArg,
    /// Seed of the copies.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Everything else, as for `join` (the address and code are not used).
    #[command(flatten)]
    pub client: ClientArgs,
}

/// Arguments of `join`.
#[derive(clap::Args, Debug, Clone)]
pub struct JoinArgs {
    /// The server's address (its join endpoint), e.g. 127.0.0.1:5757; asked for by speech when left out.
    pub addr: Option<SocketAddr>,
    /// The join code the host gave; asked for by speech when left out (then a wrong code is asked again).
    #[arg(long)]
    pub code: Option<String>,
    /// Device, window, audio and bot settings.
    #[command(flatten)]
    pub client: ClientArgs,
}

/// Settings shared by `join` and `practice`.
#[derive(clap::Args, Debug, Clone)]
pub struct ClientArgs {
    /// The haptic device: sim (keyboard moves its hand), trace:FILE (replay), hid or hid:/dev/hidrawN,
    /// falcon or falcon:FIRMWARE (a Novint Falcon on USB), haply or haply:ws://HOST:PORT/ (a Haply
    /// Inverse3 through the Haply Inverse Service; default ws://localhost:10001/).
    #[arg(long, default_value = "sim")]
    pub device: DeviceChoice,
    /// Device preset the sim device copies (e.g. touch, falcon, premium); default Phantom Desktop.
    #[arg(long)]
    pub preset: Option<String>,
    /// How forces are rendered: auto (the 3-DOF proxy on a device that renders no torque, else
    /// volumetric), volumetric or proxy.
    #[arg(long, value_enum, default_value_t = RenderingChoice::Auto)]
    pub rendering: RenderingChoice,
    /// Record the device's every tick (state read, force commanded) to this trace file (`haptico trace
    /// v2`, docs/haptics.md): replay it with `--device trace:FILE` or `haptic-bench --replay FILE`.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// No window: sound and touch only.
    #[arg(long)]
    pub headless: bool,
    /// Play by touch automatically (needs the sim device).
    #[arg(long)]
    pub bot: bool,
    /// Spheres per copy's sphere tree.
    #[arg(long, default_value_t = 3000)]
    pub spheres: usize,
    /// Cache built sphere trees here (default: the system's cache directory).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Where the sound goes.
    #[arg(long, value_enum, default_value_t = AudioChoice::Card)]
    pub audio: AudioChoice,
    /// Also write what was heard to this WAV file (with `--audio memory`).
    #[arg(long)]
    pub wav: Option<PathBuf>,
    /// Place sounds with interaural time and level differences instead of the HRTF (this run only).
    #[arg(long)]
    pub no_hrtf: bool,
    /// The settings file (default: settings.toml in the platform's config directory, e.g.
    /// ~/.config/phantom-heist/); the settings menu saves there.
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Speech rate for this run, words per minute (80–400).
    #[arg(long, value_parser = clap::value_parser!(u32).range(80..=400))]
    pub speech_rate: Option<u32>,
    /// Speech volume for this run, percent.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100))]
    pub speech_volume: Option<u8>,
    /// Museum and contact sound volume for this run, percent.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100))]
    pub sound_volume: Option<u8>,
    /// Earcon volume for this run, percent.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100))]
    pub earcon_volume: Option<u8>,
    /// The partner's voice volume for this run, percent.
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=100))]
    pub voice_volume: Option<u8>,
    /// The push-to-talk key for this run.
    #[arg(long, value_enum)]
    pub talk_key: Option<crate::settings::TalkKey>,
    /// The walkie-talkie's microphone.
    #[command(flatten)]
    pub voice: heist_voice::VoiceFlags,
    /// Real-time priority (1–99) for the haptic thread, if the system allows it.
    #[arg(long)]
    pub realtime: Option<i32>,
    /// Spectator window: save a screenshot to this PNG after `--shot-after` frames, then quit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames before the screenshot.
    #[arg(long, default_value_t = 150)]
    pub shot_after: u32,
}

impl ClientArgs {
    /// The client's settings from the arguments.
    pub fn settings(&self) -> Result<PhantomSettings, String> {
        if self.bot && self.device != DeviceChoice::Sim {
            return Err("--bot moves the hand itself: it needs --device sim".into());
        }
        let cache = self.cache.clone().or_else(default_cache);
        let overrides = crate::settings::Overrides {
            speech_rate: self.speech_rate,
            speech_volume: self.speech_volume,
            sound_volume: self.sound_volume,
            earcon_volume: self.earcon_volume,
            voice_volume: self.voice_volume,
            hrtf: self.no_hrtf.then_some(false),
            talk_key: self.talk_key,
        };
        let prefs = crate::settings::plugin::Settings::load(
            self.settings.clone().or_else(crate::settings::default_path),
            &overrides,
        );
        Ok(PhantomSettings {
            bot: self.bot,
            haptics: HapticsSettings {
                device: self.device.clone(),
                preset: self.preset.clone(),
                record: self.record.clone(),
                rendering: self.rendering,
                spheres: self.spheres,
                cache_dir: cache,
                realtime_priority: self.realtime,
            },
            audio: AudioSettings {
                output: match self.audio {
                    AudioChoice::Card => AudioOutput::SoundCard,
                    AudioChoice::Memory => AudioOutput::Background(self.wav.clone()),
                },
                spatial: if prefs.run.hrtf { SpatialMode::Hrtf } else { SpatialMode::TimeLevel },
                ..Default::default()
            },
            prefs,
            voice: self.voice.settings(self.audio == AudioChoice::Card),
        })
    }
}

/// `$XDG_CACHE_HOME/phantom-heist/ist` or `~/.cache/phantom-heist/ist`.
pub fn default_cache() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("phantom-heist").join("ist"))
}

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
        app.add_systems(Update, (leave_after_a_result, tell_the_link));
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
    state: Res<PhantomState>,
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

/// Says why the server let us go, or that it went silent (3 s without a packet), came back or is gone;
/// that the client tries to get back in or gave up; quits 3 s after the connection ended for good, so the
/// last line is heard.
#[allow(clippy::too_many_arguments)]
fn tell_the_link(
    link: Res<heist_client::Link>,
    inbox: Res<heist_client::Inbox>,
    reconnect: Res<heist_client::Reconnect>,
    time: Res<Time<Real>>,
    mut news: Local<heist_client::notice::LinkNews>,
    mut ended_at: Local<Option<f32>>,
    leaving: Res<heist_client::Leaving>,
    mut speaker: NonSendMut<crate::speech::Speaker>,
    (mut audio, mut was, mut told_gave_up): (
        NonSendMut<crate::audio::AudioEngine>,
        Local<heist_client::Link>,
        Local<bool>,
    ),
    mut exit: MessageWriter<AppExit>,
) {
    use heist_client::Link;
    let now = time.elapsed_secs();
    let lines = news.news(*link, &inbox, &leaving, &reconnect);
    // Earcons with the words: lost (and given up) low, back rising.
    let gave_up = matches!(*reconnect, heist_client::Reconnect::GaveUp(_));
    match (*was, *link) {
        (Link::Up, Link::Silent | Link::Gone) if leaving.since.is_none() => {
            audio.earcon(crate::audio::synth::Earcon::LinkDown)
        }
        (Link::Silent, Link::Up) => audio.earcon(crate::audio::synth::Earcon::LinkUp),
        _ if gave_up && !*told_gave_up => audio.earcon(crate::audio::synth::Earcon::LinkDown),
        _ => {}
    }
    *told_gave_up = gave_up;
    *was = *link;
    for line in lines {
        speaker.say(line);
    }
    if heist_client::connection_over(*link, &inbox, &reconnect) {
        ended_at.get_or_insert(now);
    }
    if ended_at.is_some_and(|t| now - t > 3.0) {
        exit.write(AppExit::Success);
    }
}

/// Runs `join`: asks by speech for what the command line left out, gets a token (saying every failure
/// and what to do next, and asking again where that helps), connects, plays until the session ends.
pub fn join(args: &JoinArgs) -> anyhow::Result<()> {
    let mut settings = args.client.settings().map_err(anyhow::Error::msg)?;
    let mut prompter = crate::prompt::Prompter::new(&mut settings)?;
    check_device(&mut prompter, &settings)?;
    let cache = heist_client::SeatCache::in_default_dir();
    let joined = get_a_seat(&mut prompter, args, cache.as_ref());
    let (addr, joining) = match joined {
        Ok(j) => j,
        Err(e) => {
            prompter.finish_speaking(Duration::from_secs(30));
            return Err(e);
        }
    };
    let (audio, speaker) = prompter.into_parts();
    let mut app = app(settings, args.client.headless, None, Some((audio, speaker)))?;
    args.client.request_shot(&mut app);
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, joining.token)?;
    heist_client::hold_seat(&mut app, cache, addr, Role::Phantom);
    app.run();
    Ok(())
}

/// Looks for a real device before anything else, and says what was found and what to do with it, or what
/// is wrong (then the program ends: a seat is no use without the device).
pub fn check_device(prompter: &mut crate::prompt::Prompter, settings: &PhantomSettings) -> anyhow::Result<()> {
    match crate::device::check(&settings.haptics.device) {
        Ok(Some(setup)) => prompter.say(setup),
        Ok(None) => {}
        Err(e) => {
            let said = match &e {
                crate::ClientError::Device(why) => format!("The haptic device is not ready: {why}."),
                other => other.to_string(),
            };
            prompter.say(said);
            prompter.finish_speaking(Duration::from_secs(30));
            return Err(e.into());
        }
    }
    Ok(())
}

/// The token for a seat: from the command line's address and code, or from spoken questions.
fn get_a_seat(
    prompter: &mut crate::prompt::Prompter,
    args: &JoinArgs,
    cache: Option<&heist_client::SeatCache>,
) -> anyhow::Result<(SocketAddr, heist_client::Joining)> {
    use crate::prompt::Next;
    let asking = args.code.is_none();
    let no_answer = || anyhow::anyhow!("joining: no answer (the input ended, or the client was stopped)");
    let mut addr = args.addr;
    let mut code = args.code.clone();
    loop {
        let at = match addr {
            Some(a) => a,
            None => *addr.insert(prompter.ask_address().ok_or_else(no_answer)?),
        };
        // A kept seat is taken back without the code.
        let kept = cache.is_some_and(|c| c.load(at, Role::Phantom).is_some());
        let typed = match (&code, kept) {
            (Some(c), _) => c.clone(),
            (None, true) => String::new(),
            (None, false) => code.insert(prompter.ask_code().ok_or_else(no_answer)?).clone(),
        };
        if kept {
            prompter.say("Taking your seat back.");
        }
        let result = match heist_client::join_or_resume(at, &typed, Role::Phantom, cache, Duration::from_secs(5)) {
            // The kept seat is gone and no code was typed yet: ask for it.
            Err(heist_client::JoinError::BadCode(_)) if typed.is_empty() => {
                code = None;
                continue;
            }
            other => other,
        };
        let e = match result {
            Ok(joining) => return Ok((at, joining)),
            Err(e) => e,
        };
        let (said, next) = crate::prompt::advice(&e);
        prompter.say(said);
        let error = anyhow::Error::new(e).context(format!("joining {at} as Phantom"));
        match next {
            _ if !asking => return Err(error),
            Next::Address => addr = None,
            Next::Code => code = None,
            Next::Wait(s) => {
                prompter.finish_speaking(Duration::from_secs(30));
                std::thread::sleep(Duration::from_secs(u64::from(s.min(300))));
                code = None;
            }
            Next::Stop => return Err(error),
        }
    }
}

/// Runs `practice`: looks for a real device first, as `join` and `host` do, then feels copies on the bench.
pub fn practice(args: &PracticeArgs) -> anyhow::Result<()> {
    let mut settings = args.client.settings().map_err(anyhow::Error::msg)?;
    let mut prompter = crate::prompt::Prompter::new(&mut settings)?;
    check_device(&mut prompter, &settings)?;
    let kind = args.kind.into();
    let practice = Some(crate::practice::Practice::new(kind, args.seed));
    let mut app = app(settings, args.client.headless, practice, Some(prompter.into_parts()))?;
    args.client.request_shot(&mut app);
    app.run();
    Ok(())
}

impl ClientArgs {
    /// Asks the spectator window for a screenshot when `--screenshot` was given.
    pub fn request_shot(&self, app: &mut App) {
        #[cfg(feature = "spectator")]
        if let Some(path) = &self.screenshot {
            app.insert_resource(crate::spectator::ShotRequest { path: path.clone(), after_frames: self.shot_after });
        }
        #[cfg(not(feature = "spectator"))]
        if self.screenshot.is_some() {
            log::warn!("built without the spectator window: no screenshot");
            let _ = app;
        }
    }
}

/// Runs `devices`.
pub fn devices() -> anyhow::Result<()> {
    println!("Device presets (for --preset with the sim device):");
    for p in haptico::presets::all() {
        println!(
            "  {:<28} {:.1} N peak, {} N/m, {}",
            p.name,
            p.peak_force_n,
            p.max_stiffness_n_per_m,
            if p.renders_torque() { "forces and torques" } else { "forces only" }
        );
    }
    match haptico::hid::list_devices() {
        Ok(list) if list.is_empty() => println!("No HID haptic device found (see docs/haptics.md for the udev rule)."),
        Ok(list) => {
            println!("HID devices (for --device hid:PATH):");
            for d in list {
                println!("  {} {:04x}:{:04x} {:?} {}", d.path, d.vendor_id, d.product_id, d.kind, d.product);
            }
        }
        Err(e) => println!("HID devices could not be listed: {e}"),
    }
    match haptico::falcon::usb::count_plugged_in() {
        Ok(0) => println!("No Novint Falcon on USB."),
        Ok(n) => println!("Novint Falcon on USB ({n}): renders forces (--device falcon[:FIRMWARE])."),
        Err(e) => println!("USB devices could not be listed (for a Falcon): {e}"),
    }
    let url = haptico::haply::DEFAULT_URL;
    match haptico::haply::probe(url, Duration::from_secs(1)) {
        Ok(list) if list.is_empty() => println!("The Haply Inverse Service at {url} lists no Inverse3."),
        Ok(list) => {
            for d in list {
                println!(
                    "Haply Inverse3 {} at {url}: renders forces (--device haply){}",
                    d.device_id,
                    if d.calibrated { "" } else { "; not calibrated yet" }
                );
            }
        }
        Err(_) => println!("No Haply Inverse Service at {url} (for an Inverse3)."),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bot_refuses_a_device_it_cannot_steer() {
        let cli = Cli::try_parse_from([
            "client_haptic",
            "join",
            "127.0.0.1:5757",
            "--code",
            "ABCD",
            "--bot",
            "--device",
            "hid",
        ])
        .expect("parses");
        let Command::Join(args) = cli.command else { panic!("join") };
        assert!(args.client.settings().unwrap_err().contains("--device sim"));
    }

    #[test]
    fn a_bad_device_is_a_clear_usage_error() {
        let err =
            Cli::try_parse_from(["client_haptic", "join", "127.0.0.1:5757", "--code", "A", "--device", "phantom"])
                .unwrap_err()
                .to_string();
        assert!(err.contains("sim, trace:FILE, hid[:PATH], falcon[:FIRMWARE] or haply[:URL]"), "{err}");
    }
}
