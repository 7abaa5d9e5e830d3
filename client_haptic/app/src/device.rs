//! Which haptic device the client drives, and how the game thread steers a simulated hand.
//!
//! You need this module to open the device named on the command line (`sim`, `trace:FILE`,
//! `hid[:PATH]`, `falcon[:FIRMWARE]`, `haply[:URL]`: haptico's [`DeviceChoice`], opened by haptico), to check a real one before a session and watch it
//! during one ([`check`], [`reading`], [`Guide`]), and, with the sim device, to move its hand from the keyboard or from the bot through
//! a [`HandControl`] (latest [`HandGoal`] through a triple buffer: the haptic thread never waits).

use glam::Vec3;
use haptico::choice::Opened;
use haptico::{DeviceLink, DeviceSpecs};

use crate::error::ClientError;

pub use haptico::DeviceChoice;

/// Where a real device's grip is put in the device frame when the game starts: where the simulated hand
/// starts, in front of the workbench.
pub const START: Vec3 = Vec3::new(0.0, 0.06, 0.07);

pub use haptico::steer::{HandControl, HandGoal, SteeredSim};

/// The device preset a simulated device copies (`--preset`; default the Phantom Desktop: 7.9 N, 1000 N/m).
pub fn preset(name: Option<&str>) -> Result<DeviceSpecs, ClientError> {
    match name {
        None => Ok(haptico::presets::phantom_desktop()),
        Some(n) => {
            haptico::presets::by_name(n).ok_or_else(|| ClientError::Device(format!("no device preset named {n:?}")))
        }
    }
}

/// What the link says now, for a [`Guide`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reading {
    /// What to tell the player once the device stopped answering (no force reaches it any more), else
    /// `None`.
    pub lost: Option<&'static str>,
    /// For a device that must be homed (the Falcon): whether every arm is home.
    pub homed: Option<bool>,
    /// The grip is read outside the device's workspace, so the safety layer keeps forces off.
    pub outside_workspace: bool,
}

/// What the player hears while the grip is read outside the device's workspace.
pub const BACK_TO_THE_MIDDLE: &str =
    "Move the grip back towards the middle of its reach: forces stay off while it is that far out.";

/// What the player hears when it is back.
pub const BACK_IN_REACH: &str = "The grip is back in reach: you will feel the copies now.";

/// What a real device's I/O thread tells of its link (haptico's [`DeviceLink`]) now.
pub fn reading(link: &DeviceLink) -> Reading {
    match link {
        DeviceLink::Local => Reading::default(),
        DeviceLink::Falcon(s) => Reading {
            lost: s.disconnected().then_some(
                "The Falcon stopped answering: no force reaches it. Check its cable and power, then start again.",
            ),
            // Homing starts once the firmware answers.
            homed: (s.replies() > 0).then(|| s.homed().iter().all(|&h| h)),
            outside_workspace: false,
        },
        DeviceLink::Haply(s) => Reading {
            lost: s.disconnected().then_some(
                "The Haply service went away: no force reaches the Inverse3. Check that the Haply Inverse \
                     Service runs and the Inverse3 is on, then start again.",
            ),
            homed: None,
            outside_workspace: false,
        },
    }
}

/// What to tell the player of a real device as a session goes on: the homing instruction when homing
/// starts and every [`haptico::falcon::homing::Homing::REMIND`] while it lasts, once that forces are on
/// when it is done; once homed, [`BACK_TO_THE_MIDDLE`] when the grip is read outside the workspace (and
/// as often while it stays out), [`BACK_IN_REACH`] when it returns; and once that the device was lost
/// (nothing after that).
#[derive(Debug, Default)]
pub struct Guide {
    instructed_at_s: Option<f64>,
    outside_told_at_s: Option<f64>,
    lost_told: bool,
}

impl Guide {
    /// What to say at `now_s` (seconds, any monotonic clock), given the link's `reading`.
    pub fn next(&mut self, reading: Reading, now_s: f64) -> Option<&'static str> {
        if self.lost_told {
            return None;
        }
        if let Some(notice) = reading.lost {
            self.lost_told = true;
            return Some(notice);
        }
        let remind = haptico::falcon::homing::Homing::REMIND.as_secs_f64();
        match (reading.homed, self.instructed_at_s) {
            (Some(false), None) => {
                self.instructed_at_s = Some(now_s);
                return Some(haptico::falcon::homing::INSTRUCTION);
            }
            (Some(false), Some(t)) if now_s - t >= remind => {
                self.instructed_at_s = Some(now_s);
                return Some(haptico::falcon::homing::INSTRUCTION);
            }
            // Before homing the grip's position means nothing.
            (Some(false), _) => return None,
            (Some(true), Some(_)) => {
                self.instructed_at_s = None;
                return Some("The Falcon is homed: you will feel the copies now.");
            }
            _ => {}
        }
        match (reading.outside_workspace, self.outside_told_at_s) {
            (true, Some(t)) if now_s - t < remind => None,
            (true, _) => {
                self.outside_told_at_s = Some(now_s);
                Some(BACK_TO_THE_MIDDLE)
            }
            (false, Some(_)) => {
                self.outside_told_at_s = None;
                Some(BACK_IN_REACH)
            }
            (false, None) => None,
        }
    }
}

/// Looks for a real device before a session, quickly (a few seconds at most): what to tell the player to
/// do when it is there (`None` for simulated, recorded and HID devices, opened as they are), or what is
/// wrong, to be said before anything else happens.
pub fn check(choice: &DeviceChoice) -> Result<Option<String>, ClientError> {
    match choice {
        DeviceChoice::Falcon(_) => match haptico::falcon::usb::count_plugged_in() {
            Ok(0) => Err(ClientError::Device(
                "no Novint Falcon is plugged in: plug its USB cable and its power in, then start again".into(),
            )),
            Ok(_) => Ok(Some(format!(
                "Found the Novint Falcon. When the game starts its light is red until it is homed: {}",
                haptico::falcon::homing::INSTRUCTION
            ))),
            Err(e) => Err(ClientError::Device(format!(
                "no Novint Falcon found, as USB devices could not be listed ({e}): plug it in, check that this \
                 program may read USB devices (docs/haptics.md has the udev rule), then start again"
            ))),
        },
        DeviceChoice::Haply(url) => {
            let listed = haptico::haply::probe(url, haptico::haply::CONNECT_TIMEOUT)
                .map_err(|e| ClientError::Device(format!("the Haply Inverse3: {e}")))?;
            let Some(first) = listed.first() else {
                return Err(ClientError::Device(format!(
                    "the Haply Inverse Service at {url} lists no Inverse3: plug it in and switch it on, then start again"
                )));
            };
            let calibrated = if first.calibrated { "" } else { " The service says it is not calibrated yet." };
            Ok(Some(format!(
                "Found the Haply Inverse3.{calibrated} Hold its grip still where you want to play: the game centres \
                 on it when it starts."
            )))
        }
        DeviceChoice::Sim | DeviceChoice::Trace(_) | DeviceChoice::Hid(_) => Ok(None),
    }
}

/// Opens the chosen device (haptico's [`haptico::choice::open`]), a simulated hand resting at [`START`]:
/// the device, with `sim` the control that moves its hand, and its link to watch ([`reading`]).
pub fn open(choice: &DeviceChoice, specs: DeviceSpecs) -> Result<Opened, ClientError> {
    haptico::choice::open(choice, specs, START).map_err(|e| ClientError::Device(e.to_string()))
}

/// The pose a goal asks for, in the device frame of `map`.
pub fn to_device(map: &haptic_rig::WorkspaceMap, goal: HandGoal) -> HandGoal {
    let d = |p: Vec3| map.to_device(&haptic_common::Pose::from_translation(p)).translation;
    match goal {
        HandGoal::Hold(p) => HandGoal::Hold(map.to_device(&p)),
        HandGoal::Line { from, to, duration_s, start_us } => {
            HandGoal::Line { from: d(from), to: d(to), duration_s, start_us }
        }
        HandGoal::Orbit { centre, radius, start_rad, period_s, turns, start_us } => {
            HandGoal::Orbit { centre: d(centre), radius: radius / map.scale, start_rad, period_s, turns, start_us }
        }
        HandGoal::Taps { centre, r_out, r_in, n, tap_s, start_us } => {
            HandGoal::Taps { centre: d(centre), r_out: r_out / map.scale, r_in: r_in / map.scale, n, tap_s, start_us }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_falcon_that_is_not_plugged_in_is_refused_at_once_with_what_to_check() {
        let start = std::time::Instant::now();
        let Err(e) = open(&DeviceChoice::Falcon(None), haptico::presets::falcon()) else {
            panic!("no Falcon is plugged into a test machine");
        };
        let e = e.to_string();
        assert!(e.contains("Novint Falcon (USB 0403:cb48)") && !e.contains('\n'), "{e}");
        assert!(start.elapsed() < std::time::Duration::from_secs(5), "answered in {:?}", start.elapsed());
    }

    #[test]
    fn an_inverse3_service_that_is_not_running_is_refused_within_seconds_with_what_to_start() {
        let port = std::net::TcpListener::bind("127.0.0.1:0").expect("binds").local_addr().expect("port").port();
        let choice = DeviceChoice::Haply(format!("ws://127.0.0.1:{port}/"));
        let start = std::time::Instant::now();
        let e = check(&choice).expect_err("nothing listens there").to_string();
        assert!(e.contains("no Haply Inverse Service at ws://127.0.0.1:") && e.contains("start the service"), "{e}");
        let Err(opened) = open(&choice, haptico::presets::inverse3()) else { panic!("opened a closed port") };
        assert_eq!(opened.to_string(), e, "the check and the open say the same");
        assert!(!e.contains('\n') && start.elapsed() < std::time::Duration::from_secs(5), "{:?}", start.elapsed());
        assert!(reading(&DeviceLink::Local).lost.is_none());
    }

    #[test]
    fn the_guide_repeats_the_homing_instruction_until_homed_then_tells_forces_are_on_and_a_loss_once() {
        let homing = Reading { homed: Some(false), ..Reading::default() };
        let homed = Reading { homed: Some(true), ..Reading::default() };
        let lost = Reading { lost: Some("gone"), homed: Some(true), ..Reading::default() };
        let instruction = Some(haptico::falcon::homing::INSTRUCTION);
        let mut g = Guide::default();
        // Before the firmware answers, nothing; then the instruction at once and every 8 s.
        assert_eq!(g.next(Reading::default(), 0.0), None);
        assert_eq!(g.next(homing, 1.0), instruction);
        assert_eq!(g.next(homing, 8.9), None);
        assert_eq!(g.next(homing, 9.0), instruction);
        assert_eq!(g.next(homed, 10.0), Some("The Falcon is homed: you will feel the copies now."));
        assert_eq!(g.next(homed, 30.0), None, "said once");
        // An arm loses home: homing again.
        assert_eq!(g.next(homing, 31.0), instruction);
        assert_eq!(g.next(lost, 32.0), Some("gone"));
        assert_eq!(g.next(lost, 33.0), None, "the loss is said once, and nothing after it");
        assert_eq!(g.next(homing, 60.0), None);
        // A device without homing only ever hears of a loss.
        let mut g = Guide::default();
        assert_eq!(g.next(Reading::default(), 0.0), None);
        assert_eq!(reading(&DeviceLink::Local), Reading::default());
    }

    #[test]
    fn the_guide_sends_a_grip_read_out_of_reach_back_to_the_middle_but_not_before_homing() {
        let out = Reading { outside_workspace: true, ..Reading::default() };
        let mut g = Guide::default();
        assert_eq!(g.next(out, 0.0), Some(BACK_TO_THE_MIDDLE));
        assert_eq!(g.next(out, 7.9), None);
        assert_eq!(g.next(out, 8.0), Some(BACK_TO_THE_MIDDLE), "again while it stays out");
        assert_eq!(g.next(Reading::default(), 9.0), Some(BACK_IN_REACH));
        assert_eq!(g.next(Reading::default(), 20.0), None, "said once");
        // A Falcon that is not homed reads anything: only the homing instruction is heard.
        let mut g = Guide::default();
        let homing_out = Reading { homed: Some(false), outside_workspace: true, ..Reading::default() };
        assert_eq!(g.next(homing_out, 0.0), Some(haptico::falcon::homing::INSTRUCTION));
        assert_eq!(g.next(homing_out, 1.0), None);
        let homed_out = Reading { homed: Some(true), outside_workspace: true, ..Reading::default() };
        assert_eq!(g.next(homed_out, 2.0), Some("The Falcon is homed: you will feel the copies now."));
        assert_eq!(g.next(homed_out, 2.1), Some(BACK_TO_THE_MIDDLE));
    }
}
