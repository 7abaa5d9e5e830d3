//! Route planning over the room graph: rooms are convex, so a route is a chain of door crossings.

use std::collections::BinaryHeap;

use glam::Vec2;

use super::Level;

/// How far before and after a door a route places its waypoints, metres.
const DOOR_APPROACH: f32 = 0.7;

/// The rooms and the doors between them, ready for route queries.
#[derive(Clone, Debug)]
pub struct NavGraph {
    rooms: Vec<(Vec2, Vec2)>,
    /// For each room: (door index, other room, door centre, unit normal pointing into the other room).
    links: Vec<Vec<(usize, usize, Vec2, Vec2)>>,
    door_gain: Vec<f32>,
}

#[derive(Clone, Copy, PartialEq)]
struct Entry {
    cost: f32,
    room: usize,
}
impl Eq for Entry {}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other.cost.total_cmp(&self.cost).then(other.room.cmp(&self.room))
    }
}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl NavGraph {
    /// Builds the graph of `level` (unknown room names in doors are skipped; validation reports them).
    pub fn new(level: &Level) -> Self {
        let rooms: Vec<_> = level.rooms.iter().map(|r| (r.min, r.max)).collect();
        let mut links = vec![Vec::new(); rooms.len()];
        let mut door_gain = Vec::with_capacity(level.doors.len());
        for (i, door) in level.doors.iter().enumerate() {
            door_gain.push(if door.open { 1.0 } else { door.attenuation });
            let (Some(a), Some(b)) = (level.room_index(&door.between.0), level.room_index(&door.between.1)) else {
                continue;
            };
            let into = |r: usize| {
                let (min, max) = rooms[r];
                let c = (min + max) * 0.5;
                let d = c - door.at;
                if level.rooms[a].shared_wall_axis(&level.rooms[b], door.at) == Some(true) {
                    Vec2::new(d.x.signum(), 0.0)
                } else {
                    Vec2::new(0.0, d.y.signum())
                }
            };
            links[a].push((i, b, door.at, into(b)));
            links[b].push((i, a, door.at, into(a)));
        }
        Self { rooms, links, door_gain }
    }

    /// Index of the room containing `p`, if any.
    pub fn room_at(&self, p: Vec2) -> Option<usize> {
        self.rooms.iter().position(|(min, max)| p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y)
    }

    /// The first room that cannot be reached from `start`, if any.
    pub fn unreachable_room(&self, start: usize) -> Option<usize> {
        let mut seen = vec![false; self.rooms.len()];
        let mut stack = vec![start];
        while let Some(r) = stack.pop() {
            if std::mem::replace(&mut seen[r], true) {
                continue;
            }
            stack.extend(self.links[r].iter().map(|l| l.1));
        }
        seen.iter().position(|s| !s)
    }

    /// Waypoints from `from` to `to` (excluding `from`, ending at `to`), or None when either point is
    /// outside every room.
    pub fn route(&self, from: Vec2, to: Vec2) -> Option<Vec<Vec2>> {
        self.route_avoiding(from, to, |_| 1.0)
    }

    /// Like [`NavGraph::route`], but walking through room `r` costs `room_cost(r)` times its length
    /// (e.g. to keep away from rooms where guards are).
    pub fn route_avoiding(&self, from: Vec2, to: Vec2, room_cost: impl Fn(usize) -> f32) -> Option<Vec<Vec2>> {
        let (start, goal) = (self.room_at(from)?, self.room_at(to)?);
        let mut points = Vec::new();
        for (_, door, into) in self.room_path(start, goal, from, |_, room| 1.0 / room_cost(room).max(0.05))? {
            points.push(door - into * DOOR_APPROACH);
            points.push(door + into * DOOR_APPROACH);
        }
        points.push(to);
        // Standing in a doorway already: the approach point behind us is no longer needed.
        if points.len() >= 2 && from.distance(points[1]) <= points[0].distance(points[1]) {
            points.remove(0);
        }
        Some(points)
    }

    /// Length of the route from `from` to `to`, metres (infinite when there is none).
    pub fn route_length(&self, from: Vec2, to: Vec2) -> f32 {
        self.route(from, to).map_or(f32::INFINITY, |points| Self::path_length(from, &points))
    }

    /// The length of the walk from `from` through `points` in turn (a [`NavGraph::route`]), metres.
    pub fn path_length(from: Vec2, points: &[Vec2]) -> f32 {
        let mut at = from;
        let mut length = 0.0;
        for &p in points {
            length += at.distance(p);
            at = p;
        }
        length
    }

    /// The rooms a door leads to from room `room`, each once.
    pub fn neighbours(&self, room: usize) -> Vec<usize> {
        let mut out: Vec<usize> = self.links.get(room).map_or_else(Vec::new, |l| l.iter().map(|l| l.1).collect());
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The centre of room `room`.
    pub fn room_centre(&self, room: usize) -> Option<Vec2> {
        self.rooms.get(room).map(|(min, max)| (*min + *max) * 0.5)
    }

    /// Centres of all rooms.
    pub fn room_centres(&self) -> impl Iterator<Item = Vec2> + '_ {
        self.rooms.iter().map(|(min, max)| (*min + *max) * 0.5)
    }

    /// How loud a sound of `loudness` (audible radius, metres) is at `listener`: the radius left after
    /// walking the shortest door path, scaled by every closed door's attenuation. Positive means heard.
    /// A listener farther than `loudness` in a straight line cannot hear it whatever the doors (a path is
    /// never shorter than the straight line, an attenuation never above 1): the margin is then the
    /// straight line's, negative, without walking the doors.
    pub fn heard_margin(&self, source: Vec2, listener: Vec2, loudness: f32) -> f32 {
        let straight = loudness - source.distance(listener);
        if straight < 0.0 {
            return straight;
        }
        self.walked_margin(source, listener, loudness)
    }

    /// [`NavGraph::heard_margin`] along the door path, always walked.
    fn walked_margin(&self, source: Vec2, listener: Vec2, loudness: f32) -> f32 {
        let (Some(a), Some(b)) = (self.room_at(source), self.room_at(listener)) else {
            return f32::NEG_INFINITY;
        };
        let Some(path) = self.room_path(a, b, source, |door, _| self.door_gain[door]) else {
            return f32::NEG_INFINITY;
        };
        let mut gain = 1.0;
        let mut at = source;
        let mut distance = 0.0;
        for (door, p, _) in &path {
            gain *= self.door_gain[*door];
            distance += at.distance(*p);
            at = *p;
        }
        distance += at.distance(listener);
        loudness * gain - distance
    }

    /// Dijkstra over rooms; cost is walking distance between door centres divided by
    /// `weight(door, room entered)`.
    fn room_path(
        &self,
        start: usize,
        goal: usize,
        from: Vec2,
        weight: impl Fn(usize, usize) -> f32,
    ) -> Option<Vec<(usize, Vec2, Vec2)>> {
        let n = self.rooms.len();
        let mut best = vec![f32::INFINITY; n];
        let mut at = vec![from; n];
        let mut prev: Vec<Option<(usize, usize, Vec2, Vec2)>> = vec![None; n];
        let mut heap = BinaryHeap::new();
        best[start] = 0.0;
        heap.push(Entry { cost: 0.0, room: start });
        while let Some(Entry { cost, room }) = heap.pop() {
            if room == goal {
                break;
            }
            if cost > best[room] {
                continue;
            }
            for &(door, next, p, into) in &self.links[room] {
                let c = cost + at[room].distance(p) / weight(door, next).max(0.05);
                if c < best[next] {
                    best[next] = c;
                    at[next] = p;
                    prev[next] = Some((room, door, p, into));
                    heap.push(Entry { cost: c, room: next });
                }
            }
        }
        if !best[goal].is_finite() {
            return None;
        }
        let mut path = Vec::new();
        let mut r = goal;
        while let Some((p_room, door, p, into)) = prev[r] {
            path.push((door, p, into));
            r = p_room;
        }
        path.reverse();
        Some(path)
    }
}

#[cfg(test)]
mod tests {
    use super::super::WallSet;
    use super::*;

    #[test]
    fn every_route_between_room_centres_is_walkable() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        let walls = WallSet::new(&level);
        for a in &level.rooms {
            for b in &level.rooms {
                let route = nav.route(a.centre(), b.centre()).expect("route");
                let mut p = a.centre();
                for w in route {
                    assert!(walls.walls.iter().all(|s| !s.intersects(p, w)), "{p:?} -> {w:?} crosses a wall");
                    p = w;
                }
            }
        }
    }

    #[test]
    fn a_closed_door_muffles_sound() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        let door = level.doors.iter().find(|d| !d.open).expect("a closed door");
        let ra = &level.rooms[level.room_index(&door.between.0).unwrap()];
        let rb = &level.rooms[level.room_index(&door.between.1).unwrap()];
        let s = door.at + (ra.centre() - door.at).normalize() * 1.0;
        let l = door.at + (rb.centre() - door.at).normalize() * 1.0;
        let mut open_level = level.clone();
        open_level.doors.iter_mut().for_each(|d| d.open = true);
        let open = NavGraph::new(&open_level).heard_margin(s, l, 10.0);
        assert!(nav.heard_margin(s, l, 10.0) < open - 5.0);
    }

    /// The shortcut for listeners out of a straight line's reach is sound: the walked margin is never
    /// above the straight line's, so a sound it calls unheard is unheard.
    #[test]
    fn no_walked_margin_exceeds_the_straight_lines() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        let mut points: Vec<Vec2> = level.rooms.iter().map(|r| r.centre()).collect();
        points.extend(level.doors.iter().map(|d| d.at));
        points.extend(level.cases.iter().map(|c| c.at));
        let mut walked = 0;
        for &s in &points {
            for &l in &points {
                for loudness in [2.0, 6.0, 12.0, 25.0] {
                    let margin = nav.walked_margin(s, l, loudness);
                    assert!(margin <= loudness - s.distance(l) + 1e-4, "{s:?} -> {l:?} at {loudness}: {margin}");
                    walked += usize::from(margin.is_finite());
                }
            }
        }
        assert!(walked > 1000, "the pairs were walked ({walked})");
    }
}
