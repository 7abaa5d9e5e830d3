//! The `client_vr` command line: `join ADDR --code CODE` and `xr-check`; [`app`] builds the same Bevy app
//! the tests drive by hand.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::view::screenshot::{Screenshot, save_to_disk};
use bevy::window::{PresentMode, WindowResolution};
use clap::{Parser, Subcommand, ValueEnum};
use heist_audio::{AudioOutput, AudioSettings, SpatialMode};
use heist_bots::ViveStyle;
use heist_client::ClientNetPlugin;
use heist_shared::protocol::{Role, TICK_HZ};

use crate::bot::BotStyle;
use crate::client::{ViveClientPlugin, ViveSettings, ViveState};
use crate::intent::InputSource;
use crate::xr::{Handedness, Locomotion, XrOptions, XrProbe};

/// The command line.
#[derive(Parser, Debug)]
#[command(name = "client_vr", about = "Phantom Heist: join as Vive, the sighted player, in VR or on the desktop")]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Join a session as Vive.
    Join(JoinArgs),
    /// Host a session (the server runs in this client, or on a `heist-server serve` with --server) and
    /// join it as Vive; the join code for Phantom is printed and shown on the HUD.
    Host(HostArgs),
    /// Say whether XR mode would start here, and why not.
    XrCheck,
}

/// Where the sound goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AudioChoice {
    /// The sound card (falls back to memory when there is none).
    Card,
    /// Rendered in memory only (with `--wav`, into that file too).
    Memory,
    /// No sound.
    Off,
}

/// How the bot plays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StyleArg {
    /// Sneaks past guards.
    Careful,
    /// Runs for it.
    Reckless,
    /// Stands still.
    Idle,
}

/// Whether to try XR.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum XrChoice {
    /// XR when a runtime with a headset is there, else the desktop.
    Auto,
    /// Always the desktop.
    Off,
}

/// Arguments of `join`.
#[derive(clap::Args, Debug, Clone)]
pub struct JoinArgs {
    /// The server's address (its join endpoint), e.g. 127.0.0.1:5757.
    pub addr: SocketAddr,
    /// The join code the host printed.
    #[arg(long)]
    pub code: String,
    /// How to play.
    #[command(flatten)]
    pub vive: ViveArgs,
}

/// Arguments of `host`.
#[derive(clap::Args, Debug, Clone)]
pub struct HostArgs {
    /// Where and what to host.
    #[command(flatten)]
    pub host: heist_server::embedded::HostFlags,
    /// How to play.
    #[command(flatten)]
    pub vive: ViveArgs,
}

/// How Vive plays: mode, bot, XR, sound, walkie-talkie (shared by `join` and `host`).
#[derive(clap::Args, Debug, Clone)]
pub struct ViveArgs {
    /// No window and no XR: the game logic only (with --bot, a bot plays).
    #[arg(long)]
    pub headless: bool,
    /// The Vive bot plays through this client's intents, prediction and reconciliation.
    #[arg(long)]
    pub bot: bool,
    /// The bot's style.
    #[arg(long, value_enum, default_value_t = StyleArg::Careful)]
    pub style: StyleArg,
    /// Say ready as soon as the level arrives.
    #[arg(long)]
    pub ready: bool,
    /// XR or desktop.
    #[arg(long, value_enum, default_value_t = XrChoice::Auto)]
    pub xr: XrChoice,
    /// XR locomotion.
    #[arg(long, value_enum, default_value_t = Locomotion::Teleport)]
    pub locomotion: Locomotion,
    /// XR: play seated.
    #[arg(long)]
    pub seated: bool,
    /// XR: the main hand.
    #[arg(long, value_enum, default_value_t = Handedness::Right)]
    pub hand: Handedness,
    /// Where the sound goes (default: the card, or off when headless).
    #[arg(long, value_enum)]
    pub audio: Option<AudioChoice>,
    /// With `--audio memory`, also write the sound to this WAV file.
    #[arg(long)]
    pub wav: Option<PathBuf>,
    /// Time and level differences instead of HRTF.
    #[arg(long)]
    pub no_hrtf: bool,
    /// Save a screenshot (PNG) here once the museum is shown, then quit; in XR mode the left eye's
    /// image, as the headset showed it.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to wait before the screenshot (lavapipe needs ~120).
    #[arg(long, default_value_t = 150)]
    pub shot_after: u32,
    /// Window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Quit this many seconds after the heist ends.
    #[arg(long, default_value_t = 5.0)]
    pub quit_after: f32,
    /// The walkie-talkie's microphone.
    #[command(flatten)]
    pub voice: heist_voice::VoiceFlags,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or_else(|| format!("size `{s}`: expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|n| (64..=8192).contains(n));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("size `{s}`: width and height must be whole numbers from 64 to 8192")),
    }
}

/// How the app presents the game.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Mode {
    /// No window.
    Headless,
    /// A window, keyboard and mouse.
    Desktop,
    /// The headset.
    Xr,
}

/// Decides the mode; the line says which and why (logged once at start-up).
pub fn decide_mode(args: &ViveArgs, probe: impl FnOnce() -> XrProbe) -> (Mode, String) {
    if args.headless {
        return (Mode::Headless, "headless mode: no window, no XR".into());
    }
    if args.xr == XrChoice::Off {
        return (Mode::Desktop, "desktop mode: XR turned off with --xr off".into());
    }
    let p = probe();
    (if p.ready() { Mode::Xr } else { Mode::Desktop }, p.line())
}

impl ViveArgs {
    /// The walkie-talkie's settings these arguments ask for (no sound card: no microphone either).
    pub fn voice_settings(&self) -> heist_voice::VoiceSettings {
        self.voice.settings(self.audio_choice() == AudioChoice::Card)
    }

    /// The client settings these arguments ask for.
    pub fn settings(&self, mode: &Mode) -> ViveSettings {
        let input = match (self.bot, mode) {
            (true, _) => InputSource::Bot,
            (false, Mode::Xr) => InputSource::Xr,
            (false, _) => InputSource::Desktop,
        };
        ViveSettings { input, ready_at_once: self.ready, quit_after_end_s: Some(self.quit_after) }
    }

    fn audio_choice(&self) -> AudioChoice {
        self.audio.unwrap_or(if self.headless { AudioChoice::Off } else { AudioChoice::Card })
    }

    fn audio(&self) -> Option<AudioSettings> {
        let output = match self.audio_choice() {
            AudioChoice::Off => return None,
            AudioChoice::Card => AudioOutput::SoundCard,
            AudioChoice::Memory => AudioOutput::Background(self.wav.clone()),
        };
        let spatial = if self.no_hrtf { SpatialMode::TimeLevel } else { SpatialMode::Hrtf };
        Some(AudioSettings { output, spatial, ..Default::default() })
    }
}

/// Save a screenshot after some frames of the museum, then quit.
#[derive(Resource, Clone, Debug)]
pub struct ShotRequest {
    /// Where the PNG goes.
    pub path: PathBuf,
    /// Frames of the museum to wait.
    pub after_frames: u32,
    /// Shoot the headset's left eye (XR mode) instead of the window.
    pub left_eye: bool,
}

/// The Vive client's Bevy app, not yet connected.
pub fn app(args: &ViveArgs, mode: &Mode) -> anyhow::Result<App> {
    let mut app = App::new();
    let settings = args.settings(mode);
    let style = match args.style {
        StyleArg::Careful => ViveStyle::Careful,
        StyleArg::Reckless => ViveStyle::Reckless,
        StyleArg::Idle => ViveStyle::Idle,
    };
    app.insert_resource(BotStyle(style));
    let window = Window {
        title: "Phantom Heist — Vive".into(),
        resolution: WindowResolution::new(args.size.0, args.size.1),
        present_mode: PresentMode::AutoVsync,
        ..default()
    };
    match mode {
        Mode::Headless => {
            app.add_plugins(MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(1.0 / TICK_HZ))))
                .add_plugins(bevy::log::LogPlugin::default());
        }
        Mode::Desktop => {
            app.add_plugins(
                DefaultPlugins
                    .set(WindowPlugin { primary_window: Some(window), ..default() })
                    .set(RenderPlugin { synchronous_pipeline_compilation: true, ..default() }),
            );
        }
        Mode::Xr => {
            app.add_plugins(
                bevy_mod_openxr::add_xr_plugins(DefaultPlugins)
                    // The mirror window at `--size` (add_xr_plugins puts in its own 1280x720 window), never
                    // waiting for the display: the headset's frame loop (xrWaitFrame) paces the app.
                    .set(WindowPlugin {
                        primary_window: Some(Window { present_mode: PresentMode::AutoNoVsync, ..window }),
                        ..default()
                    })
                    .set(bevy_mod_openxr::init::OxrInitPlugin {
                        app_info: bevy_mod_openxr::types::AppInfo {
                            name: "Phantom Heist".into(),
                            version: bevy_mod_openxr::types::Version(0, 1, 0),
                        },
                        ..default()
                    }),
            );
        }
    }
    app.add_plugins(ClientNetPlugin)
        .add_plugins(ViveClientPlugin { settings })
        .add_plugins(heist_client::signals::SignalsPlugin);
    if *mode != Mode::Headless {
        app.add_plugins((crate::world::WorldPlugin, crate::hud::HudPlugin { wrist: *mode == Mode::Xr }));
    }
    match mode {
        Mode::Desktop => {
            app.add_plugins(crate::desktop::DesktopPlugin { input: !args.bot });
        }
        Mode::Xr if args.bot => {
            info!("--bot in XR: the bot plays; the headset is carried with its body and looks its way");
            app.add_plugins(crate::xr::XrViewPlugin { follow_body: true });
        }
        Mode::Xr => {
            let options = XrOptions { locomotion: args.locomotion, seated: args.seated, hand: args.hand };
            app.add_plugins((crate::xr::XrInputPlugin { options }, crate::xr::XrViewPlugin { follow_body: false }));
        }
        Mode::Headless => {}
    }
    if let Some(audio) = args.audio() {
        crate::sound::add(&mut app, &audio)?;
    }
    app.insert_resource(args.voice_settings()).add_plugins((heist_voice::VoicePlugin, crate::walkie::WalkiePlugin));
    if let Some(path) = &args.screenshot {
        app.insert_resource(ShotRequest {
            path: path.clone(),
            after_frames: args.shot_after,
            left_eye: *mode == Mode::Xr,
        })
        .add_systems(Update, shoot);
    }
    Ok(app)
}

fn shoot(
    mut commands: Commands,
    shot: Res<ShotRequest>,
    state: Res<ViveState>,
    mut frames: Local<u32>,
    mut requested: Local<bool>,
    mut exit: MessageWriter<AppExit>,
) {
    if state.level.is_none() {
        return;
    }
    *frames += 1;
    if *frames == shot.after_frames && !*requested {
        *requested = true;
        info!("screenshot: saving {}", shot.path.display());
        // In XR the left eye's swapchain image (what the headset shows); on the desktop the window.
        let target = if shot.left_eye {
            Screenshot::texture_view(bevy::camera::ManualTextureViewHandle(bevy_mod_openxr::render::XR_TEXTURE_INDEX))
        } else {
            Screenshot::primary_window()
        };
        commands.spawn(target).observe(save_to_disk(shot.path.clone()));
    }
    // Saving happens a few frames later, on another thread: wait for the file.
    if *frames > shot.after_frames + 5 && shot.path.exists() || *frames > shot.after_frames + 600 {
        exit.write(AppExit::Success);
    }
}

/// Runs `join`: decides the mode, gets a token, connects, plays until the session ends.
pub fn join(args: &JoinArgs) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let mode = announce_mode(&args.vive);
    let cache = heist_client::SeatCache::in_default_dir();
    let joining =
        heist_client::join_or_resume(args.addr, &args.code, Role::Vive, cache.as_ref(), Duration::from_secs(5))
            .with_context(|| format!("joining {} as Vive", args.addr))?;
    play(&args.vive, &mode, joining.token, cache, args.addr, None)
}

/// Runs `host`: starts a server here (or creates a session on `--server`), prints the join code for
/// Phantom, joins as Vive and plays until the session ends.
pub fn host(args: &HostArgs) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let mode = announce_mode(&args.vive);
    let (advertised, endpoint, code, token) = match args.host.server {
        Some(server) => {
            let (code, token) = heist_client::create_session(server, Role::Vive, Duration::from_secs(5))
                .with_context(|| format!("creating a session on {server}"))?;
            (server, server, code, token)
        }
        None => {
            let here = heist_server::embedded::start(args.host.options())?;
            let token = heist_client::request_token(here.endpoint, &here.code, Role::Vive, Duration::from_secs(5))
                .with_context(|| format!("joining the session hosted on {}", here.endpoint))?;
            (here.advertised, here.endpoint, here.code, token)
        }
    };
    let line = format!("You host the heist. Phantom joins at {advertised} with the code {code}.");
    println!("{line}");
    let cache = heist_client::SeatCache::in_default_dir();
    play(&args.vive, &mode, token, cache, endpoint, Some(line))
}

/// Decides the mode and says which and why, once.
fn announce_mode(args: &ViveArgs) -> Mode {
    let (mode, line) = decide_mode(args, crate::xr::probe_from_env);
    // Logging is not up before the app exists: this line goes to stderr directly, once.
    eprintln!("client_vr: {line}");
    mode
}

/// Builds the app, connects with `token` and plays until the session ends.
fn play(
    args: &ViveArgs,
    mode: &Mode,
    token: heist_client::ConnectToken,
    cache: Option<heist_client::SeatCache>,
    endpoint: SocketAddr,
    hosted: Option<String>,
) -> anyhow::Result<()> {
    let mut app = app(args, mode)?;
    app.world_mut().resource_mut::<crate::client::ViveState>().hosted = hosted;
    app.finish();
    app.cleanup();
    heist_client::connect(&mut app, token)?;
    heist_client::hold_seat(&mut app, cache, endpoint, Role::Vive);
    app.run();
    Ok(())
}

/// Runs `xr-check`.
pub fn xr_check() -> anyhow::Result<()> {
    println!("{}", crate::xr::probe_from_env().line());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> ViveArgs {
        let mut argv = vec!["client_vr", "join", "127.0.0.1:5757", "--code", "ABCD"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).expect("parses").command {
            Command::Join(a) => a.vive,
            _ => panic!("join"),
        }
    }

    #[test]
    fn without_a_runtime_the_client_starts_on_the_desktop_and_says_why() {
        let no_loader = || XrProbe::NoLoader { reason: "libopenxr_loader.so: not found".into() };
        let (mode, line) = decide_mode(&args(&[]), no_loader);
        assert_eq!(mode, Mode::Desktop);
        assert!(line.contains("no OpenXR loader"), "{line}");
        let no_runtime = || XrProbe::NoRuntime { reason: "XR_ERROR_RUNTIME_UNAVAILABLE".into() };
        let (mode, line) = decide_mode(&args(&[]), no_runtime);
        assert_eq!(mode, Mode::Desktop);
        assert!(line.contains("no OpenXR runtime"), "{line}");
        let ready = || XrProbe::Ready { runtime: "Monado".into() };
        assert_eq!(decide_mode(&args(&[]), ready).0, Mode::Xr);
        assert_eq!(decide_mode(&args(&["--xr", "off"]), ready).0, Mode::Desktop);
        assert_eq!(decide_mode(&args(&["--headless"]), ready).0, Mode::Headless);
    }

    #[test]
    fn the_bot_drives_the_intents_in_any_mode() {
        let a = args(&["--headless", "--bot"]);
        let s = a.settings(&Mode::Headless);
        assert_eq!(s.input, InputSource::Bot);
        assert!(!s.ready_at_once, "the bot says ready itself");
        assert_eq!(args(&[]).settings(&Mode::Xr).input, InputSource::Xr);
    }

    #[test]
    fn a_bad_window_size_is_a_clear_usage_error() {
        let err = Cli::try_parse_from(["client_vr", "join", "127.0.0.1:1", "--code", "A", "--size", "big"])
            .expect_err("a usage error")
            .to_string();
        assert!(err.contains("expected WIDTHxHEIGHT"), "{err}");
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert!(parse_size("0x480").is_err());
    }
}
