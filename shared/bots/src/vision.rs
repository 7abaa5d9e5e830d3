//! The Vive bot's model of what a guard can see (a cautious copy of the server's rule, with margins).

use glam::Vec2;
use heist_shared::level::WallSet;
use heist_shared::protocol::{GuardAlert, GuardView};

/// Guard sight range, metres (the server's value).
const RANGE: f32 = 5.5;
/// Half of the vision cone, radians.
const HALF_ANGLE: f32 = 0.7;
/// Extra metres the bot keeps away from the cone's edge.
const RANGE_MARGIN: f32 = 2.5;
/// Extra radians the bot keeps away from the cone's edge.
const ANGLE_MARGIN: f32 = 0.3;

fn wrap(a: f32) -> f32 {
    (a + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI
}

/// True when `guard` could see someone at `p` (crouching or not), with the bot's safety margins.
pub fn could_see(guard: &GuardView, p: Vec2, crouching: bool, alarm: u8, walls: &WallSet) -> bool {
    let chasing = guard.alert == GuardAlert::Chasing;
    let d = p - guard.position;
    let dist = d.length();
    // Guards turn fast at the ends of their routes: close up, assume they look every way.
    let all_round = if crouching { 2.5 } else { 3.5 };
    if dist < all_round {
        return walls.line_of_sight(guard.position, p);
    }
    let mut range = RANGE * (1.0 + 0.1 * f32::from(alarm)) * if chasing { 1.5 } else { 1.0 };
    if crouching {
        range *= 0.6;
    }
    let half = if chasing { 1.4 } else { HALF_ANGLE };
    dist <= range + RANGE_MARGIN
        && wrap(d.y.atan2(d.x) - guard.facing).abs() <= half + ANGLE_MARGIN
        && walls.line_of_sight(guard.position, p)
}
