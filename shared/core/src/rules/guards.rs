//! What the guards can do on each difficulty: speeds, sight, hearing, the radio, how many patrol, and
//! how long a heist lasts. One source for the server's guards and for the Vive bot's forecasts (which
//! plan with what a player may know: the difficulty and its published numbers, never a guard's state).
//!
//! You need this module to tune the guards or add a difficulty. A level file may carry its own tuning
//! per difficulty ([`DifficultyTable`]); otherwise [`Difficulty::tuning`] gives the built-in one.

use serde::{Deserialize, Serialize};

/// How hard a heist is, chosen per session.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Difficulty {
    /// Fewer, slower, shorter-sighted guards who do not radio; more time.
    Easy,
    /// The museum as designed.
    #[default]
    Normal,
    /// Faster, sharper guards who radio from farther; less time.
    Hard,
}

impl Difficulty {
    /// Every difficulty, easiest first.
    pub const ALL: [Difficulty; 3] = [Difficulty::Easy, Difficulty::Normal, Difficulty::Hard];

    /// Its name as typed on a command line and written in logs.
    pub fn name(self) -> &'static str {
        match self {
            Difficulty::Easy => "easy",
            Difficulty::Normal => "normal",
            Difficulty::Hard => "hard",
        }
    }

    /// The built-in tuning of this difficulty.
    pub fn tuning(self) -> GuardTuning {
        let normal = GuardTuning::default();
        match self {
            Difficulty::Normal => normal,
            Difficulty::Easy => GuardTuning {
                patrol_speed: normal.patrol_speed * 0.85,
                investigate_speed: normal.investigate_speed * 0.85,
                chase_speed: normal.chase_speed * 0.85,
                sight_range: normal.sight_range * 0.8,
                sight_half_angle: normal.sight_half_angle * 0.85,
                hearing: 0.8,
                suspicion_rate: 0.75,
                radio_range_m: 0.0,
                guards: Some(2),
                time_scale: 1.25,
                evidence_alarm_cap: 0,
                ..normal
            },
            Difficulty::Hard => GuardTuning {
                patrol_speed: normal.patrol_speed * 1.1,
                investigate_speed: normal.investigate_speed * 1.1,
                chase_speed: normal.chase_speed * 1.05,
                sight_range: normal.sight_range * 1.15,
                sight_half_angle: normal.sight_half_angle * 1.1,
                hearing: 1.1,
                suspicion_rate: 1.25,
                radio_range_m: normal.radio_range_m * 2.0,
                radio_delay_s: normal.radio_delay_s * 0.5,
                time_scale: 0.85,
                // Not 2: at alarm 2 these guards would chase at 2.73 × 1.3 = 3.55 m/s, faster than Vive
                // runs, and a running Vive must be able to get away (docs/rules.md, "Difficulty").
                evidence_alarm_cap: 1,
                ..normal
            },
        }
    }
}

impl std::fmt::Display for Difficulty {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Difficulty {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "easy" => Ok(Difficulty::Easy),
            "normal" => Ok(Difficulty::Normal),
            "hard" => Ok(Difficulty::Hard),
            other => Err(format!("`{other}` is no difficulty: easy, normal or hard")),
        }
    }
}

/// What the guards can do. Every speed in m/s, every distance in metres, every angle in radians.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GuardTuning {
    /// Patrol walking speed (default 1.1).
    pub patrol_speed: f32,
    /// Speed while investigating, searching or returning (default 1.4).
    pub investigate_speed: f32,
    /// Speed while chasing (default 2.6: below Vive's run, so a running Vive can get away).
    pub chase_speed: f32,
    /// Sight range (default 5.5; ×1.5 while chasing, ×0.6 on a crouching target).
    pub sight_range: f32,
    /// Half of the vision cone (default 0.7; 1.4 while chasing).
    pub sight_half_angle: f32,
    /// Anyone this close is noticed whatever the facing (default 1.2).
    pub notice_radius: f32,
    /// Multiplies the audible radius of every noise for these guards (default 1).
    pub hearing: f32,
    /// Multiplies how fast a glimpse turns into certainty (default 1).
    pub suspicion_rate: f32,
    /// How far a guard's radio call reaches, from the caller (default 20; 0: the guards do not radio).
    pub radio_range_m: f32,
    /// Seconds between a guard seeing something and the others hearing the call (default 2).
    pub radio_delay_s: f32,
    /// How many of the level's guards are on duty, in the level's order (default: all).
    pub guards: Option<usize>,
    /// Multiplies the level's time limit (default 1).
    pub time_scale: f32,
    /// Highest alarm level that found evidence (a broken case) raises the museum to (default 1; wrong
    /// verdicts raise it further, up to the lockdown).
    pub evidence_alarm_cap: u8,
}

/// Guards' sight range while chasing, as a multiple of the normal one.
pub const CHASE_SIGHT_FACTOR: f32 = 1.5;
/// Guards' half-angle of view while chasing, as a multiple of the normal one.
pub const CHASE_ANGLE_FACTOR: f32 = 2.0;
/// Sight range on a crouching target, as a multiple of the normal one.
pub const CROUCH_SIGHT_FACTOR: f32 = 0.6;
/// Spots a search after a sighting covers at most: the spot and the rooms next to it
/// (`level::patrol::search_spots`), dealt among the guards who answer the radio (`patrol::orders`).
pub const SEARCH_SPOTS: usize = 4;
/// Spots a search for whoever broke a case covers: the case and the room next to it nearest to it.
pub const EVIDENCE_SPOTS: usize = 2;
/// How long a searching guard looks around at each spot, seconds.
pub const SEARCH_LOOK_S: f32 = 2.0;
/// A guard walking to a spot (a noise, a search spot, his round's waypoint) is there this close, metres.
pub const ARRIVED_M: f32 = 0.8;
/// How long a guard looks around where he heard or glimpsed something before going back to his round
/// (or searching), seconds.
pub const LOOK_AROUND_S: f32 = 3.0;

/// How fast a guard turns, rad/s (a guard at the end of his round sweeps his look round this fast).
pub const GUARD_TURN_RATE: f32 = 4.0;
/// How far a guard turns, radians (positive: anticlockwise), to face a direction `diff` (wrapped to
/// −π..π) away: the short way round, but an about-turn — within 0.05 rad of π either way — always
/// anticlockwise, so which way a guard sweeps his look at the end of his round is a published rule.
pub fn about_turn(diff: f32) -> f32 {
    if diff < 0.05 - std::f32::consts::PI { diff + std::f32::consts::TAU } else { diff }
}

/// Each alarm level makes the guards walk this much faster (a fraction of their speed).
pub const ALARM_HASTE_PER_LEVEL: f32 = 0.15;
/// Each alarm level makes the guards see this much farther (a fraction of their range).
pub const ALARM_SIGHT_PER_LEVEL: f32 = 0.1;
/// Each alarm level makes the guards hear this much farther (a fraction of every noise's radius).
pub const ALARM_HEARING_PER_LEVEL: f32 = 0.25;

impl Default for GuardTuning {
    fn default() -> Self {
        Self {
            patrol_speed: 1.1,
            investigate_speed: 1.4,
            chase_speed: 2.6,
            sight_range: 5.5,
            sight_half_angle: 0.7,
            notice_radius: 1.2,
            hearing: 1.0,
            suspicion_rate: 1.0,
            radio_range_m: 20.0,
            radio_delay_s: 2.0,
            guards: None,
            time_scale: 1.0,
            evidence_alarm_cap: 1,
        }
    }
}

impl GuardTuning {
    /// A guard's speed at `alarm` for a state whose calm speed is `speed` (patrol, investigate or chase).
    pub fn hasted(&self, speed: f32, alarm: u8) -> f32 {
        speed * (1.0 + ALARM_HASTE_PER_LEVEL * f32::from(alarm))
    }

    /// How far a guard sees at `alarm`, metres, chasing or not, on a target crouching or not.
    pub fn sight_range_at(&self, alarm: u8, chasing: bool, crouching: bool) -> f32 {
        let chase = if chasing { CHASE_SIGHT_FACTOR } else { 1.0 };
        let crouch = if crouching { CROUCH_SIGHT_FACTOR } else { 1.0 };
        self.sight_range * chase * crouch * (1.0 + ALARM_SIGHT_PER_LEVEL * f32::from(alarm))
    }

    /// Half of the vision cone, radians, chasing or not.
    pub fn half_angle(&self, chasing: bool) -> f32 {
        if chasing { CHASE_ANGLE_FACTOR * self.sight_half_angle } else { self.sight_half_angle }
    }

    /// Multiplies every noise's audible radius for a guard at `alarm`.
    pub fn hearing_at(&self, alarm: u8) -> f32 {
        self.hearing * (1.0 + ALARM_HEARING_PER_LEVEL * f32::from(alarm))
    }

    /// The first value out of its sensible range, as "what: why"; `None` when all are fine.
    pub fn out_of_range(&self) -> Option<String> {
        let positive = [
            ("patrol_speed", self.patrol_speed),
            ("investigate_speed", self.investigate_speed),
            ("chase_speed", self.chase_speed),
            ("sight_range", self.sight_range),
            ("sight_half_angle", self.sight_half_angle),
            ("hearing", self.hearing),
            ("suspicion_rate", self.suspicion_rate),
            ("time_scale", self.time_scale),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Some(format!("{name} must be a positive number, got {v}"));
            }
        }
        for (name, v) in [
            ("notice_radius", self.notice_radius),
            ("radio_range_m", self.radio_range_m),
            ("radio_delay_s", self.radio_delay_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Some(format!("{name} must be zero or more, got {v}"));
            }
        }
        if self.sight_half_angle > std::f32::consts::PI {
            return Some(format!("sight_half_angle must be at most π, got {}", self.sight_half_angle));
        }
        if self.evidence_alarm_cap >= crate::rules::ALARM_LOCKDOWN {
            return Some(format!(
                "evidence_alarm_cap must be below the lockdown level {}, got {}",
                crate::rules::ALARM_LOCKDOWN,
                self.evidence_alarm_cap
            ));
        }
        if self.guards == Some(0) {
            return Some("guards must be at least 1".into());
        }
        None
    }
}

/// A level's own tuning for each difficulty (each one given replaces the built-in one whole; the fields
/// it leaves out take the normal defaults).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DifficultyTable {
    /// Easy.
    pub easy: Option<GuardTuning>,
    /// Normal.
    pub normal: Option<GuardTuning>,
    /// Hard.
    pub hard: Option<GuardTuning>,
}

impl DifficultyTable {
    /// The tuning of `d`: the table's, or the built-in one.
    pub fn tuning(&self, d: Difficulty) -> GuardTuning {
        let own = match d {
            Difficulty::Easy => self.easy,
            Difficulty::Normal => self.normal,
            Difficulty::Hard => self.hard,
        };
        own.unwrap_or_else(|| d.tuning())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harder_means_faster_sharper_guards_and_less_time() {
        let [e, n, h] = Difficulty::ALL.map(Difficulty::tuning);
        assert!(e.patrol_speed < n.patrol_speed && n.patrol_speed < h.patrol_speed);
        assert!(e.sight_range < n.sight_range && n.sight_range < h.sight_range);
        assert!(e.time_scale > n.time_scale && n.time_scale > h.time_scale);
        assert_eq!(e.radio_range_m, 0.0, "easy guards do not radio");
        assert!(h.radio_range_m > n.radio_range_m && h.radio_delay_s < n.radio_delay_s);
        assert!(e.evidence_alarm_cap < n.evidence_alarm_cap && n.evidence_alarm_cap <= h.evidence_alarm_cap);
        assert!(e.hearing < n.hearing && n.hearing < h.hearing && n.suspicion_rate < h.suspicion_rate);
        for t in [e, n, h] {
            assert_eq!(t.out_of_range(), None);
        }
    }

    #[test]
    fn a_running_vive_outruns_a_chasing_guard_at_any_alarm_found_evidence_can_raise() {
        for d in Difficulty::ALL {
            let t = d.tuning();
            for alarm in 0..=t.evidence_alarm_cap {
                let chase = t.hasted(t.chase_speed, alarm);
                assert!(chase < crate::rules::RUN_SPEED, "{d} at alarm {alarm}: chase at {chase} m/s");
            }
        }
    }

    #[test]
    fn the_alarm_a_chase_and_a_crouch_scale_what_a_guard_does() {
        let t = GuardTuning::default();
        assert_eq!(t.hasted(2.0, 0), 2.0);
        assert!((t.hasted(2.0, 2) - 2.0 * (1.0 + 2.0 * ALARM_HASTE_PER_LEVEL)).abs() < 1e-6);
        assert!((t.sight_range_at(0, true, false) - t.sight_range * CHASE_SIGHT_FACTOR).abs() < 1e-6);
        assert!((t.sight_range_at(0, false, true) - t.sight_range * CROUCH_SIGHT_FACTOR).abs() < 1e-6);
        assert!(t.sight_range_at(1, false, false) > t.sight_range && t.hearing_at(1) > t.hearing);
        assert_eq!(t.half_angle(true), CHASE_ANGLE_FACTOR * t.sight_half_angle);
    }

    #[test]
    fn a_difficulty_is_typed_by_name_and_a_wrong_one_says_which_there_are() {
        assert_eq!("Hard".parse::<Difficulty>(), Ok(Difficulty::Hard));
        assert!("brutal".parse::<Difficulty>().unwrap_err().contains("easy, normal or hard"));
        assert_eq!(Difficulty::Easy.to_string(), "easy");
    }

    #[test]
    fn a_levels_table_replaces_only_the_difficulties_it_names() {
        let table = DifficultyTable {
            hard: Some(GuardTuning { chase_speed: 3.0, ..Default::default() }),
            ..Default::default()
        };
        assert_eq!(table.tuning(Difficulty::Hard).chase_speed, 3.0);
        assert_eq!(table.tuning(Difficulty::Easy), Difficulty::Easy.tuning());
        let bad = GuardTuning { sight_range: -1.0, ..Default::default() };
        assert!(bad.out_of_range().is_some_and(|w| w.contains("sight_range")));
        let lockdown = GuardTuning { evidence_alarm_cap: crate::rules::ALARM_LOCKDOWN, ..Default::default() };
        assert!(lockdown.out_of_range().is_some_and(|w| w.contains("evidence_alarm_cap")));
    }
}
