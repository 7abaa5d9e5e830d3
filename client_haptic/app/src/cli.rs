//! The `client_haptic` command line: its commands and flags, and the client's settings from them. What
//! each command does is in [`crate::commands`] and [`crate::host`]; the app they run, in
//! [`crate::assemble`].

use std::net::SocketAddr;
use std::path::PathBuf;

use bevy::prelude::*;
use clap::{Parser, Subcommand, ValueEnum};

use crate::audio::{AudioOutput, AudioSettings, SpatialMode};
use crate::client::PhantomSettings;
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
    Host(HostArgs),
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

/// Arguments of `host`.
#[derive(clap::Args, Debug, Clone)]
pub struct HostArgs {
    /// Where and what to host.
    #[command(flatten)]
    pub host: heist_server::embedded::HostFlags,
    /// Device, window, audio and bot settings, as for `join`.
    #[command(flatten)]
    pub client: ClientArgs,
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
