//! Game constants both sides must agree on (speeds, reach, limits). The full rule text is docs/rules.md.

/// Vive's top speeds, m/s.
pub const WALK_SPEED: f32 = 1.6;
/// Running speed, m/s.
pub const RUN_SPEED: f32 = 3.5;
/// Crouching speed, m/s.
pub const CROUCH_SPEED: f32 = 0.8;
/// Vive's body radius for wall collision, metres.
pub const BODY_RADIUS: f32 = 0.3;
/// How far Vive reaches to break, pick up or place, metres.
pub const REACH: f32 = 1.5;
/// Most items Vive can carry at once.
pub const CARRY_LIMIT: usize = 2;
/// Farthest throw, metres.
pub const THROW_RANGE: f32 = 9.0;
/// Audible radius of breaking glass, metres.
pub const GLASS_LOUDNESS: f32 = 16.0;
/// Audible radius of a thrown object landing, metres.
pub const THUD_LOUDNESS: f32 = 12.0;
/// Audible radius of running footsteps, metres.
pub const RUN_LOUDNESS: f32 = 6.0;
/// Alarm level at which the museum locks down (the heist is lost).
pub const ALARM_LOCKDOWN: u8 = 3;
/// Distance at which a guard catches Vive, metres.
pub const CATCH_DISTANCE: f32 = 0.9;
/// Seconds the seat of a player whose connection was lost is kept for them (their seat ticket) before
/// it is given up; a running heist stands still meanwhile.
pub const SEAT_HOLD_S: f32 = 60.0;

/// Top speed of `gait`, m/s.
pub fn gait_speed(gait: crate::protocol::Gait) -> f32 {
    use crate::protocol::Gait;
    match gait {
        Gait::Walk => WALK_SPEED,
        Gait::Run => RUN_SPEED,
        Gait::Crouch => CROUCH_SPEED,
    }
}

/// Farthest Vive sees a guard in a clear line (he turns his head at will, so in every direction),
/// metres: generous, so a guard never pops into view in the middle of a gallery.
pub const VIVE_SIGHT_RANGE: f32 = 30.0;
/// Audible radius of a guard's footsteps for Vive, metres, along the door path (closed doors muffle).
pub const GUARD_STEP_LOUDNESS: f32 = 15.0;

mod guards;
pub use guards::{
    ARRIVED_M, Difficulty, DifficultyTable, EVIDENCE_SPOTS, GUARD_TURN_RATE, GuardTuning, LOOK_AROUND_S, SEARCH_LOOK_S,
    SEARCH_SPOTS, about_turn,
};
