//! Walls derived from rooms and doors: movement collision and line of sight on the floor plane.

use glam::Vec2;

use super::Level;
use crate::rules;

/// A wall segment on the floor plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First end, metres.
    pub a: Vec2,
    /// Second end, metres.
    pub b: Vec2,
}

impl Segment {
    /// Closest point of the segment to `p`.
    pub fn closest_point(&self, p: Vec2) -> Vec2 {
        let ab = self.b - self.a;
        let len2 = ab.length_squared();
        if len2 <= f32::EPSILON {
            return self.a;
        }
        let t = ((p - self.a).dot(ab) / len2).clamp(0.0, 1.0);
        self.a + ab * t
    }

    /// True when the open segment `p`–`q` crosses this segment.
    pub fn intersects(&self, p: Vec2, q: Vec2) -> bool {
        let d1 = self.b - self.a;
        let d2 = q - p;
        let denom = d1.perp_dot(d2);
        if denom.abs() < 1e-9 {
            return false;
        }
        let w = p - self.a;
        let t = w.perp_dot(d2) / denom;
        let u = w.perp_dot(d1) / denom;
        (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)
    }
}

/// The walls of a level: room outlines with door openings cut out, plus closed doors as
/// sight-blocking (but walkable) segments.
#[derive(Clone, Debug, Default)]
pub struct WallSet {
    /// Solid wall segments: block movement, sight and sound.
    pub walls: Vec<Segment>,
    /// Closed door leaves: block sight only.
    pub closed_doors: Vec<Segment>,
}

impl WallSet {
    /// Where a thrown object lands: aimed at `target`, at most [`rules::THROW_RANGE`] away, it flies
    /// (checked every 25 cm) until the next step would cross one of these walls or leave `level`'s rooms, and lands
    /// just before. The server throws with this and the Vive bot plans its lures with it.
    pub fn throw_landing(&self, level: &Level, from: Vec2, target: Vec2) -> Vec2 {
        let mut aim = target - from;
        if aim.length() > rules::THROW_RANGE {
            aim = aim.normalize() * rules::THROW_RANGE;
        }
        let mut landing = from;
        let steps = (aim.length() / 0.25).ceil().max(1.0) as usize;
        for s in 1..=steps {
            let p = from + aim * (s as f32 / steps as f32);
            if self.walls.iter().any(|w| w.intersects(landing, p)) || level.room_at(p).is_none() {
                break;
            }
            landing = p;
        }
        landing
    }

    /// Where Vive's body ends up after `dt` seconds of moving along `direction` (|d| ≤ 1) at `speed` m/s
    /// from `from`, sliding along these walls (his body is [`rules::BODY_RADIUS`] round). The server moves
    /// Vive with this and the Vive client predicts with it, so both agree to the bit when they see the same
    /// inputs.
    pub fn move_body(&self, from: Vec2, direction: Vec2, speed: f32, dt: f32) -> Vec2 {
        self.slide(from, direction * speed * dt, rules::BODY_RADIUS)
    }

    /// Builds the walls of `level`.
    pub fn new(level: &Level) -> Self {
        let mut walls = Vec::new();
        let mut closed_doors = Vec::new();
        for room in &level.rooms {
            let (lo, hi) = (room.min, room.max);
            let edges = [
                (Vec2::new(lo.x, lo.y), Vec2::new(hi.x, lo.y)),
                (Vec2::new(hi.x, lo.y), Vec2::new(hi.x, hi.y)),
                (Vec2::new(lo.x, hi.y), Vec2::new(hi.x, hi.y)),
                (Vec2::new(lo.x, lo.y), Vec2::new(lo.x, hi.y)),
            ];
            for (a, b) in edges {
                // Openings on this edge, as parameter intervals along it.
                let dir = (b - a).normalize();
                let len = (b - a).length();
                let mut cuts: Vec<(f32, f32)> = level
                    .doors
                    .iter()
                    .filter(|d| Segment { a, b }.closest_point(d.at).distance(d.at) < 1e-3)
                    .map(|d| {
                        let t = (d.at - a).dot(dir);
                        (t - d.width * 0.5, t + d.width * 0.5)
                    })
                    .collect();
                cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
                let mut start = 0.0;
                for (c0, c1) in cuts {
                    if c0 > start {
                        walls.push(Segment { a: a + dir * start, b: a + dir * c0 });
                    }
                    start = start.max(c1);
                }
                if start < len {
                    walls.push(Segment { a: a + dir * start, b });
                }
            }
        }
        for door in level.doors.iter().filter(|d| !d.open) {
            let ra = level.room_index(&door.between.0);
            let rb = level.room_index(&door.between.1);
            if let (Some(ra), Some(rb)) = (ra, rb) {
                let along = match level.rooms[ra].shared_wall_axis(&level.rooms[rb], door.at) {
                    Some(true) => Vec2::Y,
                    _ => Vec2::X,
                };
                let h = along * door.width * 0.5;
                closed_doors.push(Segment { a: door.at - h, b: door.at + h });
            }
        }
        Self { walls, closed_doors }
    }

    /// True when nothing solid and no closed door lies between `p` and `q`.
    pub fn line_of_sight(&self, p: Vec2, q: Vec2) -> bool {
        !self.walls.iter().chain(&self.closed_doors).any(|s| s.intersects(p, q))
    }

    /// Moves a disc of `radius` from `from` by `delta`, sliding along walls; returns the new centre.
    pub fn slide(&self, from: Vec2, delta: Vec2, radius: f32) -> Vec2 {
        let mut p = from + delta;
        // A few relaxation passes resolve corners where two walls push at once.
        for _ in 0..4 {
            let mut moved = false;
            for wall in &self.walls {
                let c = wall.closest_point(p);
                let d = p - c;
                let dist = d.length();
                if dist < radius {
                    let n = if dist > 1e-6 {
                        d / dist
                    } else {
                        // Centre exactly on the wall: push back towards where we came from.
                        let back = from - c;
                        if back.length_squared() > 1e-12 { back.normalize() } else { Vec2::X }
                    };
                    p = c + n * radius;
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        // Never tunnel: a step that would cross a wall is cancelled.
        if self.walls.iter().any(|w| w.intersects(from, p)) { from } else { p }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::level::Room;

    fn level() -> Level {
        Level::museum()
    }

    #[test]
    fn walls_leave_gaps_at_doors() {
        let level = level();
        let walls = WallSet::new(&level);
        for door in &level.doors {
            let blocked = walls.walls.iter().any(|w| w.closest_point(door.at).distance(door.at) < 0.3);
            assert!(!blocked, "door at {:?} is walled up", door.at);
        }
    }

    #[test]
    fn a_walker_cannot_pass_through_a_wall() {
        let level = level();
        let walls = WallSet::new(&level);
        let room = &level.rooms[0];
        let start = Vec2::new(room.max.x - 0.5, room.min.y + 0.7);
        let mut p = start;
        for _ in 0..200 {
            p = walls.slide(p, Vec2::new(0.05, 0.0), 0.3);
        }
        assert!(room.contains(p, 0.0), "escaped the room to {p:?}");
    }

    #[test]
    fn walls_block_sight_but_an_open_door_does_not() {
        let level = level();
        let walls = WallSet::new(&level);
        let door = level.doors.iter().find(|d| d.open).expect("an open door");
        let ra = &level.rooms[level.room_index(&door.between.0).unwrap()];
        let rb = &level.rooms[level.room_index(&door.between.1).unwrap()];
        let through = |r: &Room| door.at + (r.centre() - door.at).normalize() * 0.8;
        assert!(walls.line_of_sight(through(ra), through(rb)));
        assert!(!walls.line_of_sight(ra.min + Vec2::splat(0.5), Vec2::new(ra.min.x - 3.0, ra.min.y + 0.5)));
    }
}
