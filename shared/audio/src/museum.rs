//! What the museum sounds like, the same for both players: which game event is heard as what, from how
//! high and how loud, and whose footsteps are heard when.
//!
//! Both clients read their events and the walkers they see through this module and play what it returns
//! with [`AudioEngine::play_cue`](crate::AudioEngine::play_cue); where each listener stands (Vive in the
//! museum, turning his head; Phantom at her workbench) is theirs to say, as an offset from a floor point
//! and a height.
//!
//! The numbers, once drifted apart between the two clients, are one set here (docs/decisions.md, "One
//! museum-sound mapping"): glass at the height Vive sees the glass box, the alarm high on the wall, one
//! volume a stance for Vive's steps, whoever hears them.

use glam::Vec2;
use heist_shared::protocol::{GameEvent, GuardAlert, NoiseKind, Stance};

/// Height breaking glass is heard from, metres: the centre of a case's glass box (0.45 m high) on its
/// 1 m pedestal.
pub const GLASS_HEIGHT_M: f32 = 1.2;
/// Height of the alarm bell, metres: high on a wall, under its 3 m top.
pub const ALARM_HEIGHT_M: f32 = 2.8;
/// Height of a guard's voice (a bark), metres: his mouth.
pub const BARK_HEIGHT_M: f32 = 1.7;
/// Height of a guard's radio, metres: on his chest.
pub const RADIO_HEIGHT_M: f32 = 1.4;
/// Distance a walker covers between two footsteps, metres.
pub const STEP_EVERY_M: f32 = 0.7;
/// Volume of a guard's step (0..1, as [`Sound::Step`]): a guard walks in boots and is heard farther than
/// any step of Vive's (by the rules his steps carry 15 m, `rules::GUARD_STEP_LOUDNESS`; Vive's running 6 m).
pub const GUARD_STEP_VOLUME: f32 = 0.6;
/// Walkers whose last step is remembered at most (a level has a handful of guards; more are not tracked).
pub const MAX_WALKERS: usize = 64;

/// Volume of one of Vive's steps (0..1) in `stance`: soft crouching, louder running.
pub fn vive_step_volume(stance: Stance) -> f32 {
    match stance {
        Stance::Crouching => 0.1,
        Stance::Standing => 0.25,
        Stance::Running => 0.6,
    }
}

/// Which sound a cue plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sound {
    /// Breaking glass.
    Glass,
    /// A thrown object landing.
    Thud,
    /// A second of the alarm.
    Alarm,
    /// A footstep.
    Step {
        /// Its volume, 0..1 (amplitude: 0.5 is 6 dB down).
        volume: f32,
    },
    /// A guard's bark: suspicious, or chasing.
    Bark {
        /// Chasing (a shout) rather than suspicious (a question).
        chasing: bool,
    },
    /// A guard's radio squawk.
    Radio,
}

/// One sound in the museum: what, where on the floor and how high.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MuseumCue {
    /// The sound.
    pub sound: Sound,
    /// Where on the museum's floor, metres.
    pub at: Vec2,
    /// How high above the floor, metres.
    pub height_m: f32,
    /// What it is, for logs and tests ("glass", "guard footstep", ...).
    pub what: &'static str,
}

/// The cue a game event is heard as, if it is heard at all. Vive's steps are not among them: every
/// listener hears those from [`Steps::vive`], one a [`STEP_EVERY_M`] in his stance's volume (the
/// server's running-footsteps noise is what the guards hear, not a second step).
pub fn event_cue(event: &GameEvent) -> Option<MuseumCue> {
    let cue = |sound, at: &Vec2, height_m, what| Some(MuseumCue { sound, at: *at, height_m, what });
    match event {
        GameEvent::Noise { kind: NoiseKind::Glass, position, .. } => {
            cue(Sound::Glass, position, GLASS_HEIGHT_M, "glass")
        }
        GameEvent::Noise { kind: NoiseKind::Thud, position, .. } => cue(Sound::Thud, position, 0.0, "thud"),
        GameEvent::Noise { kind: NoiseKind::Alarm, position, .. } => Some(alarm_cue(*position)),
        GameEvent::Noise { kind: NoiseKind::Footsteps, .. } => None,
        GameEvent::GuardAlert { alert: alert @ (GuardAlert::Suspicious | GuardAlert::Chasing), position, .. } => {
            cue(Sound::Bark { chasing: *alert == GuardAlert::Chasing }, position, BARK_HEIGHT_M, "guard bark")
        }
        GameEvent::Radio { from, .. } => cue(Sound::Radio, from, RADIO_HEIGHT_M, "guard radio"),
        _ => None,
    }
}

/// The alarm's cue from `at`: when it goes up, and as the listener's client repeats it while it is up.
pub fn alarm_cue(at: Vec2) -> MuseumCue {
    MuseumCue { sound: Sound::Alarm, at, height_m: ALARM_HEIGHT_M, what: "alarm" }
}

/// Where each walker last stepped: a footstep each time one has walked [`STEP_EVERY_M`] since.
#[derive(Clone, Debug, Default)]
pub struct Steps {
    guards: Vec<(u16, Vec2)>,
    vive: Option<Vec2>,
}

impl Steps {
    /// Guard `id` is at `at`: his step, when he has walked a step's length since the last (a guard first
    /// seen makes none).
    pub fn guard(&mut self, id: u16, at: Vec2) -> Option<MuseumCue> {
        let Some(last) = self.guards.iter_mut().find(|(g, _)| *g == id).map(|(_, p)| p) else {
            if self.guards.len() < MAX_WALKERS {
                self.guards.push((id, at));
            }
            return None;
        };
        stepped(last, at).then_some(MuseumCue {
            sound: Sound::Step { volume: GUARD_STEP_VOLUME },
            at,
            height_m: 0.0,
            what: "guard footstep",
        })
    }

    /// Vive is at `at` in `stance`: his step, when he has walked a step's length since the last.
    pub fn vive(&mut self, at: Vec2, stance: Stance) -> Option<MuseumCue> {
        let last = self.vive.get_or_insert(at);
        stepped(last, at).then_some(MuseumCue {
            sound: Sound::Step { volume: vive_step_volume(stance) },
            at,
            height_m: 0.0,
            what: "vive footstep",
        })
    }
}

/// Whether a walker last stepped at `last` steps again at `at` (and `last` moves there).
fn stepped(last: &mut Vec2, at: Vec2) -> bool {
    let far = at.distance(*last) > STEP_EVERY_M;
    if far {
        *last = at;
    }
    far
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::GuardId;

    #[test]
    fn breaking_glass_is_heard_at_the_glass_box_and_the_alarm_high_on_the_wall() {
        let glass =
            event_cue(&GameEvent::Noise { kind: NoiseKind::Glass, position: Vec2::new(3.0, 4.0), loudness: 16.0 });
        assert_eq!(glass.map(|c| (c.sound, c.at, c.height_m)), Some((Sound::Glass, Vec2::new(3.0, 4.0), 1.2)));
        let alarm = event_cue(&GameEvent::Noise { kind: NoiseKind::Alarm, position: Vec2::ZERO, loudness: 30.0 });
        assert_eq!(alarm.map(|c| c.height_m), Some(ALARM_HEIGHT_M));
        assert_eq!(alarm, Some(alarm_cue(Vec2::ZERO)));
    }

    #[test]
    fn a_guard_barks_when_suspicious_or_chasing_and_says_nothing_on_patrol() {
        let alert = |alert| GameEvent::GuardAlert { guard: GuardId(1), alert, position: Vec2::ONE };
        assert_eq!(event_cue(&alert(GuardAlert::Chasing)).map(|c| c.sound), Some(Sound::Bark { chasing: true }));
        assert_eq!(event_cue(&alert(GuardAlert::Suspicious)).map(|c| c.sound), Some(Sound::Bark { chasing: false }));
        assert_eq!(event_cue(&alert(GuardAlert::Patrolling)), None);
    }

    #[test]
    fn the_servers_running_noise_is_not_a_second_footstep() {
        let run = GameEvent::Noise { kind: NoiseKind::Footsteps, position: Vec2::ONE, loudness: 6.0 };
        assert_eq!(event_cue(&run), None);
    }

    #[test]
    fn a_guard_steps_once_a_step_length_and_a_new_guard_makes_no_step() {
        let mut steps = Steps::default();
        assert_eq!(steps.guard(2, Vec2::ZERO), None, "first seen");
        assert_eq!(steps.guard(2, Vec2::new(0.5, 0.0)), None, "half a step on");
        let step = steps.guard(2, Vec2::new(0.8, 0.0)).expect("a step's length on");
        assert_eq!(
            (step.sound, step.at, step.what),
            (Sound::Step { volume: GUARD_STEP_VOLUME }, Vec2::new(0.8, 0.0), "guard footstep")
        );
        assert_eq!(steps.guard(2, Vec2::new(1.0, 0.0)), None, "counted from the last step");
        assert_eq!(steps.guard(3, Vec2::new(5.0, 0.0)), None, "another guard, first seen");
    }

    #[test]
    fn vives_steps_are_soft_crouching_and_loud_running_and_louder_than_none_of_a_guards() {
        let mut steps = Steps::default();
        assert_eq!(steps.vive(Vec2::ZERO, Stance::Running), None);
        let run = steps.vive(Vec2::new(1.0, 0.0), Stance::Running).expect("a step");
        let crouch = steps.vive(Vec2::new(2.0, 0.0), Stance::Crouching).expect("a step");
        let volume = |c: MuseumCue| match c.sound {
            Sound::Step { volume } => volume,
            other => panic!("not a step: {other:?}"),
        };
        assert!(volume(crouch) < vive_step_volume(Stance::Standing));
        assert!(vive_step_volume(Stance::Standing) < volume(run));
        assert!(volume(run) <= GUARD_STEP_VOLUME);
    }

    #[test]
    fn walkers_beyond_the_bound_are_not_remembered() {
        let mut steps = Steps::default();
        for id in 0..(MAX_WALKERS as u16 + 10) {
            steps.guard(id, Vec2::ZERO);
        }
        assert_eq!(steps.guards.len(), MAX_WALKERS);
    }
}
