//! Homing the Falcon: its encoders count from wherever the arms were at power-on until each arm has
//! been driven to its end stop, so no position (and no force) can be trusted before.
//!
//! You need this module to bring a Falcon up: ask for homing in every packet, tell the player what to
//! do ("pull the grip all the way out towards you, then push it back in"), and let forces through only
//! once all three arms report home — and again only after homing again should one lose it.

use std::time::Duration;

use super::packet::{Reply, led};

/// Where homing stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HomingState {
    /// Not every arm is home; `missing` says which are not (top, right, left).
    Homing {
        /// Arms not yet home.
        missing: [bool; 3],
    },
    /// All three arms are home: positions are right and forces may be sent.
    Homed,
}

/// What the player is told while homing, said again every [`Homing::REMIND`] until done.
pub const INSTRUCTION: &str = "Pull the Falcon's grip all the way out towards you, then push it back in.";

/// The homing state machine; fed each reply, it says what to send and what to tell the player.
#[derive(Clone, Debug)]
pub struct Homing {
    state: HomingState,
    since_us: u64,
    last_told_us: Option<u64>,
}

impl Default for Homing {
    fn default() -> Self {
        Self { state: HomingState::Homing { missing: [true; 3] }, since_us: 0, last_told_us: None }
    }
}

impl Homing {
    /// How often the instruction is repeated while homing goes on.
    pub const REMIND: Duration = Duration::from_secs(8);

    /// A Falcon not yet homed.
    pub fn new() -> Self {
        Self::default()
    }

    /// The current state.
    pub fn state(&self) -> HomingState {
        self.state
    }

    /// True when forces may be sent.
    pub fn forces_allowed(&self) -> bool {
        self.state == HomingState::Homed
    }

    /// Whether the next packet asks the firmware to home.
    pub fn request(&self) -> bool {
        !self.forces_allowed()
    }

    /// The LEDs that show the state: red while homing, green once homed.
    pub fn leds(&self) -> u8 {
        if self.forces_allowed() { led::GREEN } else { led::RED }
    }

    /// Takes a reply at `t_us`; returns the state when it changed.
    pub fn update(&mut self, reply: &Reply, t_us: u64) -> Option<HomingState> {
        let next = if reply.all_homed() {
            HomingState::Homed
        } else {
            HomingState::Homing { missing: reply.homed.map(|h| !h) }
        };
        if next == self.state {
            return None;
        }
        let was_homed = self.forces_allowed();
        self.state = next;
        if was_homed != self.forces_allowed() {
            self.since_us = t_us;
            self.last_told_us = None;
        }
        Some(next)
    }

    /// What to tell the player at `t_us`, if anything: the instruction when homing starts and every
    /// [`Homing::REMIND`] while it lasts.
    pub fn say(&mut self, t_us: u64) -> Option<&'static str> {
        if self.forces_allowed() {
            return None;
        }
        let due = self.last_told_us.is_none_or(|t| t_us >= t + Self::REMIND.as_micros() as u64);
        if due {
            self.last_told_us = Some(t_us);
        }
        due.then_some(INSTRUCTION)
    }

    /// How long the current state has lasted at `t_us`.
    pub fn lasted(&self, t_us: u64) -> Duration {
        Duration::from_micros(t_us.saturating_sub(self.since_us))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reply(homed: [bool; 3]) -> Reply {
        Reply { homed, ..Reply::default() }
    }

    #[test]
    fn forces_wait_until_all_three_arms_are_home() {
        let mut h = Homing::new();
        assert!(h.request() && !h.forces_allowed() && h.leds() == led::RED);
        assert_eq!(
            h.update(&reply([true, false, false]), 1_000),
            Some(HomingState::Homing { missing: [false, true, true] })
        );
        assert!(!h.forces_allowed());
        assert_eq!(h.update(&reply([true, false, false]), 2_000), None, "no change, no news");
        assert_eq!(h.update(&reply([true, true, true]), 3_000), Some(HomingState::Homed));
        assert!(h.forces_allowed() && !h.request() && h.leds() == led::GREEN);
    }

    #[test]
    fn an_arm_that_loses_its_home_stops_the_forces_until_homed_again() {
        let mut h = Homing::new();
        h.update(&reply([true; 3]), 0);
        assert_eq!(
            h.update(&reply([true, false, true]), 5_000_000),
            Some(HomingState::Homing { missing: [false, true, false] })
        );
        assert!(!h.forces_allowed() && h.request());
        assert_eq!(h.say(5_000_000), Some(INSTRUCTION), "told again at once");
        assert_eq!(h.lasted(6_000_000), Duration::from_secs(1));
    }

    #[test]
    fn the_instruction_is_said_at_once_then_every_eight_seconds_and_never_once_homed() {
        let mut h = Homing::new();
        assert_eq!(h.say(0), Some(INSTRUCTION));
        assert_eq!(h.say(1_000_000), None);
        assert_eq!(h.say(7_999_999), None);
        assert_eq!(h.say(8_000_000), Some(INSTRUCTION));
        h.update(&reply([true; 3]), 9_000_000);
        assert_eq!(h.say(20_000_000), None);
    }
}
