//! The teleport pointer: a ballistic arc thrown from the off hand along where it points, landing on the
//! floor, blocked by the first wall it meets, and judged valid or not before the player lets go — valid
//! when it lands inside a room, clear of the walls by a body's radius, within the teleport range, with
//! no solid wall between the body and the landing (the server walks the body there, so it must be able
//! to). Pure: the XR systems draw it ([`TeleportArc::points`]) and act on it.

use glam::{Vec2, Vec3};
use heist_shared::level::{Level, Segment, WallSet};
use heist_shared::rules::BODY_RADIUS;

use crate::museum::WALL_HEIGHT_M;
use crate::space;

/// Farthest teleport, metres.
pub const TELEPORT_RANGE_M: f32 = 4.0;
/// Speed the arc leaves the hand at, m/s (a 45° arc from the floor reaches 4.3 m).
pub const ARC_SPEED: f32 = 6.5;
/// Time between the arc's points, seconds.
pub const ARC_STEP_S: f32 = 0.02;
/// Most points an arc has (3 s of flight: it lands long before).
pub const ARC_POINTS: usize = 150;
/// Height of a closed door leaf, metres (as the world draws it).
pub const DOOR_HEIGHT_M: f32 = 2.2;

/// Why a teleport target is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refused {
    /// The arc met a wall or a closed door before landing.
    HitsWall,
    /// It landed outside every room.
    OutsideRooms,
    /// It landed within a body's radius of a wall.
    AgainstWall,
    /// It landed farther than the teleport range.
    TooFar,
    /// A solid wall lies between the body and the landing: the body could not walk there.
    NoWay,
}

/// One aim of the teleport pointer.
#[derive(Clone, Debug, PartialEq)]
pub struct TeleportArc {
    /// The arc's points, world coordinates, from the hand to where it ends.
    pub points: Vec<Vec3>,
    /// Where it ends on the floor.
    pub landing: Vec2,
    /// Whether the body may go there, or why not.
    pub verdict: Result<(), Refused>,
}

impl TeleportArc {
    /// Whether the target is valid.
    pub fn valid(&self) -> bool {
        self.verdict.is_ok()
    }
}

/// Where the floor segment `a`→`b` first crosses one of `segments`, as a fraction along it.
fn first_crossing<'a>(a: Vec2, b: Vec2, segments: impl Iterator<Item = &'a Segment>) -> Option<f32> {
    segments.filter(|s| s.intersects(a, b)).map(|s| crossing(a, b, s.a, s.b)).min_by(f32::total_cmp)
}

/// The fraction along `a`→`b` where it crosses the line through `c`, `d` (0 when parallel).
fn crossing(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> f32 {
    let (r, s) = (b - a, d - c);
    let denom = r.perp_dot(s);
    if denom.abs() < 1e-9 { 0.0 } else { ((c - a).perp_dot(s) / denom).clamp(0.0, 1.0) }
}

/// The arc from the hand at `hand` (world) thrown along `aim` (world direction), for a body standing at
/// `body` (floor).
pub fn teleport_arc(hand: Vec3, aim: Vec3, body: Vec2, level: &Level, walls: &WallSet) -> TeleportArc {
    let velocity = aim.normalize_or(Vec3::NEG_Z) * ARC_SPEED;
    let gravity = Vec3::new(0.0, -9.81, 0.0);
    let mut points = vec![hand];
    let mut verdict = Err(Refused::TooFar);
    for i in 1..ARC_POINTS {
        let t = i as f32 * ARC_STEP_S;
        let p = hand + velocity * t + gravity * (0.5 * t * t);
        let last = points[points.len() - 1];
        let (a, b) = (space::floor(last), space::floor(p));
        // A wall or door leaf in the way at the height the arc passes: the arc ends against it.
        let wall = first_crossing(a, b, walls.walls.iter()).filter(|f| last.lerp(p, *f).y < WALL_HEIGHT_M);
        let door = first_crossing(a, b, walls.closed_doors.iter()).filter(|f| last.lerp(p, *f).y < DOOR_HEIGHT_M);
        if let Some(f) = wall.into_iter().chain(door).min_by(f32::total_cmp) {
            points.push(last.lerp(p, f));
            verdict = Err(Refused::HitsWall);
            break;
        }
        if p.y <= 0.0 {
            // Down on the floor: where between the two points it touched.
            let f = if last.y > p.y { last.y / (last.y - p.y) } else { 1.0 };
            points.push(last.lerp(p, f).with_y(0.0));
            verdict = Ok(());
            break;
        }
        points.push(p);
    }
    let landing = space::floor(points[points.len() - 1]);
    if verdict.is_ok() {
        let clearance = walls.walls.iter().map(|s| s.closest_point(landing).distance(landing)).fold(f32::MAX, f32::min);
        verdict = if level.room_at(landing).is_none() {
            Err(Refused::OutsideRooms)
        } else if clearance < BODY_RADIUS {
            Err(Refused::AgainstWall)
        } else if landing.distance(body) > TELEPORT_RANGE_M {
            Err(Refused::TooFar)
        } else if walls.walls.iter().any(|s| s.intersects(body, landing)) {
            Err(Refused::NoWay)
        } else {
            Ok(())
        };
    }
    TeleportArc { points, landing, verdict }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn museum() -> (Level, WallSet) {
        let level = Level::museum();
        let walls = WallSet::new(&level);
        (level, walls)
    }

    /// The hand 1.2 m up at floor point `at`, aiming along floor angle `facing`, `pitch` radians up.
    fn aim(at: Vec2, facing: f32, pitch: f32) -> (Vec3, Vec3) {
        let flat = space::world(Vec2::new(facing.cos(), facing.sin()), 0.0);
        (space::world(at, 1.2), (flat * pitch.cos() + Vec3::Y * pitch.sin()).normalize())
    }

    #[test]
    fn an_arc_over_open_floor_falls_under_gravity_onto_a_valid_target_ahead() {
        let (level, walls) = museum();
        let body = Vec2::new(5.0, 3.0); // the lobby, 10 × 8 m
        let (hand, dir) = aim(body, 0.0, 0.0);
        let arc = teleport_arc(hand, dir, body, &level, &walls);
        assert!(arc.valid(), "{:?}", arc.verdict);
        assert!(arc.landing.x > body.x + 1.5 && (arc.landing.y - body.y).abs() < 1e-4, "ahead: {}", arc.landing);
        // Every point on the parabola: second differences are g·dt².
        for w in arc.points[..arc.points.len() - 1].windows(3) {
            let accel = (w[2] - 2.0 * w[1] + w[0]) / (ARC_STEP_S * ARC_STEP_S);
            assert!((accel - Vec3::new(0.0, -9.81, 0.0)).length() < 0.05, "{accel}");
        }
        assert_eq!(arc.points[0], hand);
        assert_eq!(arc.points.last().map(|p| p.y), Some(0.0), "it ends on the floor");
        // Aimed lower, it lands nearer.
        let (hand, low) = aim(body, 0.0, -0.3);
        assert!(teleport_arc(hand, low, body, &level, &walls).landing.x < arc.landing.x);
    }

    #[test]
    fn an_arc_into_a_wall_stops_there_and_is_refused() {
        let (level, walls) = museum();
        // The lobby's south wall is y = 0; 1 m from it, aiming south, flat.
        let body = Vec2::new(5.0, 1.0);
        let (hand, dir) = aim(body, -std::f32::consts::FRAC_PI_2, 0.0);
        let arc = teleport_arc(hand, dir, body, &level, &walls);
        assert_eq!(arc.verdict, Err(Refused::HitsWall));
        assert!(arc.landing.y.abs() < 1e-3, "it stops at the wall: {}", arc.landing);
        let end = arc.points.last().copied().unwrap_or_default();
        assert!(end.y > 0.0 && end.y < WALL_HEIGHT_M, "against the wall's face, {end}");
    }

    #[test]
    fn targets_against_a_wall_beyond_range_or_with_no_way_there_are_refused() {
        let (level, walls) = museum();
        // Just short of the lobby's south wall: lands within a body's radius of it.
        let body = Vec2::new(5.0, 1.9);
        let (hand, dir) = aim(body, -std::f32::consts::FRAC_PI_2, -0.45);
        let arc = teleport_arc(hand, dir, body, &level, &walls);
        assert_eq!(arc.verdict, Err(Refused::AgainstWall), "landing {}", arc.landing);
        // Thrown steeply up the long west gallery from its west end: lands beyond the range.
        let body = Vec2::new(11.0, 5.0);
        let (hand, dir) = aim(body, 0.0, 0.75);
        let far = teleport_arc(hand, dir, body, &level, &walls);
        assert_eq!(far.verdict, Err(Refused::TooFar), "landing {} ({} m)", far.landing, far.landing.distance(body));
        // A body standing on the far side of a wall from where a (hypothetical) arc lands: no way there.
        // From the workshop just north of the lobby's wall, an arc thrown from a hand reaching over it.
        let body = Vec2::new(2.0, 8.4);
        let down_south = Vec3::new(0.0, -0.8, 0.6);
        let over = teleport_arc(space::world(Vec2::new(2.0, 8.1), 3.2), down_south, body, &level, &walls);
        assert_eq!(over.verdict, Err(Refused::NoWay), "landing {}", over.landing);
    }

    #[test]
    fn an_arc_through_a_door_lands_in_the_next_room() {
        let (level, walls) = museum();
        // The lobby–west gallery door is at (10, 4): from (8, 4) aiming east through it.
        let body = Vec2::new(8.0, 4.0);
        let (hand, dir) = aim(body, 0.0, 0.15);
        let arc = teleport_arc(hand, dir, body, &level, &walls);
        assert!(arc.valid(), "{:?} at {}", arc.verdict, arc.landing);
        assert_eq!(level.room_at(arc.landing).map(|r| level.rooms[r].id.as_str()), Some("west_gallery"));
    }
}
