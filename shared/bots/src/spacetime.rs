//! A way through space and time: where to step and when to wait so that no guard of the [`Forecast`]
//! sees Vive on the way to its goal.
//!
//! The floor is a grid of 1 m cells (those inside a room and clear of the walls; doorways included),
//! time is ticks of [`PLAN_TICK_S`]. From where Vive stands it steps to a cell near it; from a cell it can
//! wait (crouching) or step to a neighbour walking, crouching, or running where no guard would hear it.
//! Each step takes the ticks its gait needs and costs them, plus, for every tick a guard of the
//! forecast would see Vive (in the cell it leaves for the first half of the step, the one it enters
//! for the second), ten seconds when only within the bot's caution margins and a hundred when in
//! plain sight. An A* search over (cell, tick), guided by the walking time to the goal through the
//! grid, finds the cheapest plan that ends within reach of the goal and then stays there
//! [`END_HOLD_S`] (its sightings counted too), or, when the goal is beyond the 20 s horizon or every way
//! to it is watched, the cheapest one that ends at the horizon, paying the walk still left to the
//! goal: progress while staying hidden. A plan's `seen_s` says how much it is seen (0: never);
//! `None`: Vive stands nowhere near the grid.
//!
//! You need this module to see why the Vive bot waits where it waits and goes when it goes.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec2;
use heist_shared::level::{Level, WallSet};
use heist_shared::protocol::Gait;
use heist_shared::rules;

use crate::forecast::{Forecast, Moment, Sighting};

/// Seconds per tick of a plan.
pub const PLAN_TICK_S: f32 = 0.25;
/// How far ahead a plan looks, ticks (20 s).
const HORIZON: usize = 80;
/// Seconds the end of a plan must then stay unseen (a crouching Vive there).
const END_HOLD_S: f32 = 4.0;
/// Ticks of [`END_HOLD_S`].
const HOLD: usize = (END_HOLD_S / PLAN_TICK_S) as usize;
/// Ticks one wait lasts.
const WAIT: usize = 2;
/// A plan may end this many ticks before the horizon (a step may not fit in the last ones).
const LAST: usize = 8;
/// What a tick of being seen by a guard's published sight costs a plan: a hundred seconds.
const SEEN_COST: u32 = 10 * MARGIN_COST;
/// What a tick of being seen only within the bot's caution margins costs a plan: ten seconds.
const MARGIN_COST: u32 = 40 * TICK_COST;
/// What a tick of time costs a plan; a wait costs a little more the earlier it is (less than a tick
/// more each), so that of two plans as quick the one that moves first wins and Vive does not put off
/// going from one plan to the next.
const TICK_COST: u32 = 128;
/// Ticks either side of a moment a spot seen then counts as seen within the margins (half a second).
const SLACK: usize = 2;
/// How far into either room Vive in a closed doorway is taken to be, metres.
const BODY_INTO_ROOM: f32 = 0.35;
/// Side of a cell, metres.
const CELL: f32 = 1.0;

/// The walkable floor as a grid of cells with the steps between neighbours. Built once per level.
pub struct Grid {
    /// Each cell's centre.
    points: Vec<Vec2>,
    /// The cells in a closed door's opening, and the door's normal: Vive there is a little on one
    /// side or the other (the leaf hides a point exactly on it, not a body).
    doorways: Vec<(u32, Vec2)>,
    /// Each cell's neighbours and the step's length.
    links: Vec<Vec<(u32, f32)>>,
}

impl Grid {
    /// The cells of `level` at least a body's radius (and a little) clear of `walls`, and the steps
    /// between neighbours (diagonals too) that pass no wall.
    pub fn new(level: &Level, walls: &WallSet) -> Self {
        let lo = level.rooms.iter().fold(Vec2::splat(f32::INFINITY), |a, r| a.min(r.min));
        let hi = level.rooms.iter().fold(Vec2::splat(f32::NEG_INFINITY), |a, r| a.max(r.max));
        let clear = |p: Vec2, by: f32| walls.walls.iter().all(|w| w.closest_point(p).distance(p) >= by);
        let (x0, y0) = ((lo.x / CELL).floor() as i32, (lo.y / CELL).floor() as i32);
        let (nx, ny) = (((hi.x / CELL).ceil() as i32 - x0 + 1).max(0), ((hi.y / CELL).ceil() as i32 - y0 + 1).max(0));
        let mut index = vec![u32::MAX; (nx * ny) as usize];
        let mut points = Vec::new();
        for iy in 0..ny {
            for ix in 0..nx {
                let p = Vec2::new((x0 + ix) as f32, (y0 + iy) as f32) * CELL;
                if level.room_at(p).is_some() && clear(p, rules::BODY_RADIUS + 0.05) {
                    index[(iy * nx + ix) as usize] = points.len() as u32;
                    points.push(p);
                }
            }
        }
        let cell_of = |ix: i32, iy: i32| {
            (ix >= 0 && iy >= 0 && ix < nx && iy < ny)
                .then(|| index[(iy * nx + ix) as usize])
                .filter(|&i| i != u32::MAX)
        };
        let links = points
            .iter()
            .map(|&p| {
                let (ix, iy) = ((p.x / CELL).round() as i32 - x0, (p.y / CELL).round() as i32 - y0);
                let mut out = Vec::new();
                for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let Some(j) = cell_of(ix + dx, iy + dy) else { continue };
                    let q = points[j as usize];
                    let passes = !walls.walls.iter().any(|w| w.intersects(p, q))
                        && [0.25, 0.5, 0.75].iter().all(|&f| clear(p.lerp(q, f), rules::BODY_RADIUS));
                    if passes {
                        out.push((j, p.distance(q)));
                    }
                }
                out
            })
            .collect();
        let doorways = (0..points.len())
            .filter_map(|i| {
                let p = points[i];
                walls.closed_doors.iter().find(|d| d.closest_point(p).distance(p) < 0.3).map(|d| {
                    let along = (d.b - d.a).normalize_or_zero();
                    (i as u32, Vec2::new(-along.y, along.x))
                })
            })
            .collect();
        Self { points, doorways, links }
    }

    /// How many cells.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// The cells Vive at `p` can step to in a straight line, and how far each is (those within a
    /// cell and a half, or two and a half when none is).
    fn steps_from(&self, p: Vec2, walls: &WallSet) -> Vec<(u32, f32)> {
        let within = |r: f32| -> Vec<(u32, f32)> {
            (0..self.points.len())
                .filter(|&i| {
                    self.points[i].distance(p) < r * CELL
                        && !walls.walls.iter().any(|w| w.intersects(p, self.points[i]))
                })
                .map(|i| (i as u32, self.points[i].distance(p).max(0.05)))
                .collect()
        };
        let near = within(1.5);
        if near.is_empty() { within(2.5) } else { near }
    }

    /// Ticks to walk from each cell to the nearest of `goals` through the grid (`u16::MAX`: never).
    fn walking_ticks_to(&self, goals: &[usize]) -> Vec<u16> {
        let mut ticks = vec![u16::MAX; self.points.len()];
        let mut heap = BinaryHeap::new();
        for &g in goals {
            ticks[g] = 0;
            heap.push(Reverse((0u16, g)));
        }
        while let Some(Reverse((t, c))) = heap.pop() {
            if t > ticks[c] {
                continue;
            }
            for &(n, len) in &self.links[c] {
                let nt = t.saturating_add(step_ticks(len, rules::WALK_SPEED) as u16);
                if nt < ticks[n as usize] {
                    ticks[n as usize] = nt;
                    heap.push(Reverse((nt, n as usize)));
                }
            }
        }
        ticks
    }
}

/// Ticks a step of `len` metres takes at `speed` (rounded up: the plan is never ahead of Vive).
fn step_ticks(len: f32, speed: f32) -> usize {
    (len / speed / PLAN_TICK_S - 1e-3).ceil().max(1.0) as usize
}

/// One step of a plan: leave for `to` at `leave_s` (seconds after the plan was made), at `gait`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// Where to.
    pub to: Vec2,
    /// When to leave (Vive waits, crouching, until then).
    pub leave_s: f32,
    /// When it is there.
    pub arrive_s: f32,
    /// How.
    pub gait: Gait,
}

/// A plan: its steps, and whether it ends within reach of the goal (else it only gets closer, unseen).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Way {
    /// The steps, first first.
    pub steps: Vec<Step>,
    /// The last step ends within reach of the goal.
    pub arrives: bool,
    /// How much Vive would be seen on the way and while staying at its end, in seconds within the
    /// margins (a second in plain sight counts as ten); 0: a way unseen.
    pub seen_s: f32,
}

/// Whether a crouching or standing Vive in each cell at each tick would be seen, worked out when first
/// asked.
struct Sightings<'a> {
    forecast: &'a Forecast,
    walls: &'a WallSet,
    points: &'a [Vec2],
    doorways: &'a [(u32, Vec2)],
    moments: Vec<Moment>,
    /// Per (tick, cell, crouching): 0 not known yet, 1 unseen, 2 seen.
    known: Vec<u8>,
}

impl Sightings<'_> {
    /// How `cell` is seen at `tick`, or within [`SLACK`] ticks of it (the forecast's timing is not
    /// exact: a guard's turn may come a little later, Vive may be a little behind its plan; a sighting
    /// only that near in time counts as one within the margins).
    fn seen(&mut self, cell: usize, tick: usize, crouching: bool) -> Sighting {
        let last = self.moments.len() - 1;
        let near = (tick.saturating_sub(SLACK)..=(tick + SLACK).min(last))
            .map(|t| self.seen_at(cell, t, crouching))
            .max()
            .unwrap_or(Sighting::Unseen);
        self.seen_at(cell, tick, crouching).max(near.min(Sighting::Margin))
    }

    fn seen_at(&mut self, cell: usize, tick: usize, crouching: bool) -> Sighting {
        let k = (tick * self.points.len() + cell) * 2 + usize::from(crouching);
        if self.known[k] == 0 {
            let p = self.points[cell];
            let sight = |q: Vec2| self.forecast.sighting(&self.moments[tick], q, crouching, self.walls);
            let seen = match self.doorways.iter().find(|(c, _)| *c as usize == cell) {
                Some(&(_, normal)) => sight(p + normal * BODY_INTO_ROOM).max(sight(p - normal * BODY_INTO_ROOM)),
                None => sight(p),
            };
            self.known[k] = 1 + seen as u8;
        }
        match self.known[k] {
            1 => Sighting::Unseen,
            2 => Sighting::Margin,
            _ => Sighting::Seen,
        }
    }

    /// What being in `cell` (crouching or not) at `tick` costs a plan.
    fn cost(&mut self, cell: usize, tick: usize, crouching: bool) -> u32 {
        match self.seen(cell, tick, crouching) {
            Sighting::Unseen => 0,
            Sighting::Margin => MARGIN_COST,
            Sighting::Seen => SEEN_COST,
        }
    }

    /// What staying in `cell` (crouching or not) for ticks `from..=to` costs a plan.
    fn cost_over(&mut self, cell: usize, from: usize, to: usize, crouching: bool) -> u32 {
        (from..=to).map(|t| self.cost(cell, t, crouching)).sum()
    }
}

/// The plan from `from` to within `reach` of `goal` (see the module's doc), or `None` when `from` is
/// nowhere near the grid.
pub fn plan(grid: &Grid, forecast: &Forecast, walls: &WallSet, from: Vec2, goal: Vec2, reach: f32) -> Option<Way> {
    // The grid's cells and one more: where Vive stands now (the start, stepped from only).
    let start = grid.len();
    let n = start + 1;
    let mut points = grid.points.clone();
    points.push(from);
    let first_steps = grid.steps_from(from, walls);
    if first_steps.is_empty() {
        return None;
    }
    let links = |cell: usize| if cell == start { &first_steps[..] } else { &grid.links[cell][..] };
    let goals: Vec<usize> = (0..n).filter(|&i| points[i].distance(goal) <= reach).collect();
    let mut to_goal = grid.walking_ticks_to(&goals.iter().copied().filter(|&g| g != start).collect::<Vec<_>>());
    let from_start = first_steps
        .iter()
        .map(|&(c, len)| to_goal[c as usize].saturating_add(step_ticks(len, rules::WALK_SPEED) as u16));
    to_goal.push(if goals.contains(&start) { 0 } else { from_start.min().unwrap_or(u16::MAX) });
    let ticks = HORIZON + HOLD + SLACK + 1;
    let mut sight = Sightings {
        forecast,
        walls,
        points: &points,
        doorways: &grid.doorways,
        moments: (0..ticks).map(|t| forecast.moment(t as f32 * PLAN_TICK_S)).collect(),
        known: vec![0; ticks * n * 2],
    };
    let state = |cell: usize, tick: usize| tick * n + cell;
    // The cheapest cost found to each state (ticks, plus [`SEEN_COST`] a tick seen) and how it was
    // reached: (previous state, gait), u32::MAX for none.
    let mut best = vec![u32::MAX; (HORIZON + 1) * n];
    let mut came = vec![(u32::MAX, Gait::Walk); (HORIZON + 1) * n];
    let mut heap = BinaryHeap::new();
    let h = |cell: usize| u32::from(to_goal[cell].min(u16::MAX / 2)) * TICK_COST;
    best[state(start, 0)] = 0;
    // (cost so far plus the estimate, the latest tick first, cell, whether this entry is a plan's end)
    heap.push(Reverse((h(start), Reverse(0usize), start, false)));
    let mut end = None;
    while let Some(Reverse((f, Reverse(tick), cell, last))) = heap.pop() {
        let g = best[state(cell, tick)];
        if last {
            end = Some((cell, tick, goals.contains(&cell), f));
            break;
        }
        if f > g + h(cell) {
            continue; // a cheaper way here was found since
        }
        let arrives = goals.contains(&cell);
        if arrives || tick + LAST >= HORIZON {
            // A plan may end here: at the goal, or short of it at the horizon (paying the rest of the
            // way), if staying here then is worth it.
            let stay = sight.cost_over(cell, tick + 1, tick + HOLD, true);
            heap.push(Reverse((g + stay + if arrives { 0 } else { h(cell) }, Reverse(tick), cell, true)));
        }
        let mut push = |to: usize, t: usize, cost: u32, gait: Gait, heap: &mut BinaryHeap<_>| {
            let k = state(to, t);
            if t <= HORIZON && g + cost < best[k] {
                best[k] = g + cost;
                came[k] = (state(cell, tick) as u32, gait);
                heap.push(Reverse((g + cost + h(to), Reverse(t), to, false)));
            }
        };
        if tick + WAIT <= HORIZON {
            let seen = sight.cost_over(cell, tick + 1, tick + WAIT, true);
            let early = (HORIZON - tick) as u32;
            push(cell, tick + WAIT, WAIT as u32 * TICK_COST + early + seen, Gait::Crouch, &mut heap);
        }
        for &(next, len) in links(cell) {
            let next = next as usize;
            for (gait, speed, crouching) in [
                (Gait::Run, rules::RUN_SPEED, false),
                (Gait::Walk, rules::WALK_SPEED, false),
                (Gait::Crouch, rules::CROUCH_SPEED, true),
            ] {
                let m = step_ticks(len, speed);
                if tick + m > HORIZON {
                    continue;
                }
                let at = |j: usize| if 2 * j <= m { cell } else { next };
                let quiet = gait != Gait::Run
                    || (1..=m).all(|j| !forecast.hears_running(&sight.moments[tick + j], points[at(j)]));
                if quiet {
                    let seen: u32 = (1..=m).map(|j| sight.cost(at(j), tick + j, crouching)).sum();
                    push(next, tick + m, m as u32 * TICK_COST + seen, gait, &mut heap);
                }
            }
        }
    }
    let (cell, tick, arrives, cost) = end?;
    let seen_s = (cost - tick as u32 * TICK_COST - if arrives { 0 } else { h(cell) }) as f32 / MARGIN_COST as f32;
    // Back from the end, each state with the gait it was reached at; a wait is a step that stays in
    // its cell, folded into the next step's leaving time.
    let mut chain = Vec::new();
    let mut at = state(cell, tick) as u32;
    while at != u32::MAX {
        let (prev, gait) = came[at as usize];
        chain.push((at as usize % n, at as usize / n, gait));
        at = prev;
    }
    chain.reverse();
    let mut steps: Vec<Step> = chain
        .windows(2)
        .filter(|pair| pair[0].0 != pair[1].0)
        .map(|pair| Step {
            to: points[pair[1].0],
            leave_s: pair[0].1 as f32 * PLAN_TICK_S,
            arrive_s: pair[1].1 as f32 * PLAN_TICK_S,
            gait: pair[1].2,
        })
        .collect();
    if arrives && cell != start {
        // The last little way, from the cell to the goal itself (the bot acts once within reach).
        let t = tick as f32 * PLAN_TICK_S;
        steps.push(Step { to: goal, leave_s: t, arrive_s: t + PLAN_TICK_S, gait: Gait::Walk });
    }
    Some(Way { steps, arrives, seen_s: (seen_s * PLAN_TICK_S * 4.0).floor() / 4.0 })
}

/// The gait to go at now: the plan's, unless Vive standing at `me` would be in a guard's plain sight
/// within half a second (the plan's cells and ticks are coarse at the edge of a guard's view): then it
/// creeps on (and the plan is made again if that makes it late).
pub fn safe_gait(forecast: &Forecast, walls: &WallSet, me: Vec2, gait: Gait) -> Gait {
    let in_plain_sight = |t: f32| forecast.sighting(&forecast.moment(t), me, false, walls) == Sighting::Seen;
    if gait != Gait::Crouch && [0.0, PLAN_TICK_S, 2.0 * PLAN_TICK_S].into_iter().any(in_plain_sight) {
        Gait::Crouch
    } else {
        gait
    }
}

/// What a plan says to do now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Order {
    /// Head for this point at this gait.
    Go(Vec2, Gait),
    /// Stay here, crouching (the next step leaves later, or the plan is done).
    Hold,
}

/// A plan being carried out by the clock.
#[derive(Clone, Debug)]
pub struct Timed {
    /// The plan.
    pub way: Way,
    /// When it was made (the bot's clock).
    pub made_at: f32,
    /// The goal it was made for.
    pub goal: Vec2,
    /// Steps done.
    done: usize,
}

/// Closer than this to a step's end counts as there, metres.
const THERE_M: f32 = 0.3;

impl Timed {
    /// `way`, made at `now` for `goal`.
    pub fn new(way: Way, now: f32, goal: Vec2) -> Self {
        Self { way, made_at: now, goal, done: 0 }
    }

    /// What to do at `now` standing at `me`: a step is done once Vive is there; the next one is
    /// waited for until its leaving time (a tick early at most, and only straight on from the last:
    /// the guards' timing is what keeps the way unseen), then walked (late Vive just goes on).
    pub fn order(&mut self, now: f32, me: Vec2) -> Order {
        let t = now - self.made_at;
        while let Some(step) = self.way.steps.get(self.done) {
            if me.distance(step.to) >= THERE_M {
                // A step straight on from the last may start a tick early (Vive walks a cell a little
                // faster than the plan's whole ticks); one after a wait waits for its time: that wait
                // is what lets a guard's look pass.
                let before = self.done.checked_sub(1).map_or(0.0, |i| self.way.steps[i].arrive_s);
                let straight_on = before >= step.leave_s;
                let early = if straight_on { PLAN_TICK_S } else { 0.0 };
                return if t + early + 1e-3 >= step.leave_s { Order::Go(step.to, step.gait) } else { Order::Hold };
            }
            self.done += 1;
        }
        Order::Hold
    }

    /// True when, by `forecast` (made at `now`), Vive following the rest of this plan from `me` would
    /// be seen on the way or while it stays at the end: time to plan again. Vive is taken to be where
    /// the plan has it each quarter second ([`pose_at`]), and checked a tick either side.
    pub fn seen_ahead(&self, forecast: &Forecast, walls: &WallSet, now: f32, me: Vec2) -> bool {
        let t0 = now - self.made_at;
        let steps = &self.way.steps[self.done.min(self.way.steps.len())..];
        let end = steps.last().map_or(t0, |s| s.arrive_s) + END_HOLD_S;
        let ticks = ((end - t0) / PLAN_TICK_S).floor().max(0.0) as usize;
        let moments: Vec<Moment> = (0..=ticks + 1).map(|k| forecast.moment(k as f32 * PLAN_TICK_S)).collect();
        (0..=ticks).any(|k| {
            let (at, crouching) = pose_at(steps, me, t0 + k as f32 * PLAN_TICK_S);
            moments[k.saturating_sub(1)..=k + 1].iter().any(|m| forecast.sees(m, at, crouching, walls))
        })
    }
}

/// Where `steps`, walked from `from`, have Vive at plan time `t`, and whether it crouches then (while
/// it waits, and on a crouching step).
fn pose_at(steps: &[Step], from: Vec2, t: f32) -> (Vec2, bool) {
    let mut at = from;
    for step in steps {
        if t < step.leave_s {
            return (at, true);
        }
        if t < step.arrive_s {
            let f = (t - step.leave_s) / (step.arrive_s - step.leave_s).max(1e-3);
            return (at.lerp(step.to, f), step.gait == Gait::Crouch);
        }
        at = step.to;
    }
    (at, true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forecast::{Heard, Known};
    use heist_shared::level::NavGraph;
    use heist_shared::protocol::{GuardAlert, GuardId, GuardView};
    use heist_shared::rules::GuardTuning;

    const CLARA: u16 = 1;

    struct Museum {
        level: Level,
        walls: WallSet,
        nav: NavGraph,
        grid: Grid,
        routes: Vec<Vec<Vec2>>,
        tuning: GuardTuning,
    }

    impl Museum {
        fn new() -> Self {
            let level = Level::museum();
            let walls = WallSet::new(&level);
            let grid = Grid::new(&level, &walls);
            let routes = level.guards.iter().map(|g| g.route.clone()).collect();
            Self { nav: NavGraph::new(&level), walls, grid, routes, tuning: GuardTuning::default(), level }
        }

        fn forecast(&self, guards: &[GuardView], me: Vec2) -> Forecast {
            let known = Known { tuning: &self.tuning, nav: &self.nav, routes: &self.routes, alarm: 0 };
            Forecast::new(&known, &guards.iter().collect::<Vec<_>>(), me, &Heard::default())
        }
    }

    fn guard(id: u16, at: Vec2, facing: f32) -> GuardView {
        GuardView { id: GuardId(id), name: format!("G{id}"), position: at, facing, alert: GuardAlert::Patrolling }
    }

    /// Where `way` has Vive every tick from `from` (and whether crouching), to its end and the hold.
    fn walked(way: &Way, from: Vec2) -> Vec<(f32, Vec2, bool)> {
        let end = way.steps.last().map_or(0.0, |s| s.arrive_s) + END_HOLD_S;
        (0..=(end / PLAN_TICK_S) as usize)
            .map(|k| {
                let t = k as f32 * PLAN_TICK_S;
                let (at, crouching) = pose_at(&way.steps, from, t);
                (t, at, crouching)
            })
            .collect()
    }

    #[test]
    fn the_grid_covers_every_room_and_door_and_no_step_crosses_a_wall() {
        let m = Museum::new();
        for room in &m.level.rooms {
            assert!(m.grid.points.iter().any(|p| room.contains(*p, -0.5)), "a cell inside {}", room.id);
        }
        for door in &m.level.doors {
            assert!(m.grid.points.iter().any(|p| p.distance(door.at) < 0.5), "a cell in the door at {:?}", door.at);
        }
        for (i, links) in m.grid.links.iter().enumerate() {
            for &(j, len) in links {
                let (p, q) = (m.grid.points[i], m.grid.points[j as usize]);
                assert!(!m.walls.walls.iter().any(|w| w.intersects(p, q)), "{p:?} → {q:?} crosses a wall");
                assert!((len - p.distance(q)).abs() < 1e-5 && len <= 1.5);
            }
        }
        let closed = m.level.doors.iter().filter(|d| !d.open).count();
        assert_eq!(m.grid.doorways.len(), closed, "each closed door's cell knows it is in a doorway");
    }

    #[test]
    fn with_no_guard_about_the_way_runs_through_the_doors_and_arrives() {
        let m = Museum::new();
        let (from, goal) = (m.level.vive_spawn, Vec2::new(31.0, 16.0)); // lobby → treasury
        let way = plan(&m.grid, &m.forecast(&[], from), &m.walls, from, goal, 1.0).expect("a way");
        assert!(way.arrives && way.seen_s == 0.0, "{way:?}");
        let mut at = from;
        let mut t = 0.0;
        for (i, step) in way.steps.iter().enumerate() {
            assert!(step.to.distance(at) <= 1.6, "one cell at a time: {at:?} → {:?}", step.to);
            assert!(!m.walls.walls.iter().any(|w| w.intersects(at, step.to)), "through a wall at {at:?}");
            assert!(step.leave_s >= t && step.arrive_s > step.leave_s, "in time order: {step:?}");
            if i + 1 < way.steps.len() {
                assert_eq!(step.gait, Gait::Run, "nobody hears it, nobody sees it: it runs");
            }
            (at, t) = (step.to, step.arrive_s);
        }
        assert!(at.distance(goal) < 1e-3, "ends at the goal");
    }

    #[test]
    fn a_guard_pacing_across_the_way_is_waited_out_or_crept_past_never_walked_into() {
        let m = Museum::new();
        // Clara paces z = 15 between x 13 and 33 (the sculpture hall and the treasury) and comes west
        // towards Vive, who crosses her line in the sculpture hall.
        let clara = guard(CLARA, Vec2::new(22.0, 15.0), std::f32::consts::PI);
        let (from, goal) = (Vec2::new(15.0, 11.0), Vec2::new(15.0, 20.0));
        let forecast = m.forecast(&[clara], from);
        // Walking straight over is seen: the test means something.
        let straight = (0..=40).any(|k| {
            let t = k as f32 * PLAN_TICK_S;
            let p = from.lerp(goal, (t * rules::WALK_SPEED / 10.0).min(1.0));
            forecast.sighting(&forecast.moment(t), p, false, &m.walls) == Sighting::Seen
        });
        assert!(straight, "a straight walk across is seen");
        let way = plan(&m.grid, &forecast, &m.walls, from, goal, 1.0).expect("a way");
        assert!(way.arrives && way.seen_s == 0.0, "{way:?}");
        for (t, p, crouching) in walked(&way, from) {
            let seen = forecast.sighting(&forecast.moment(t), p, crouching, &m.walls);
            assert_eq!(seen, Sighting::Unseen, "seen at {p:?} after {t} s: {way:?}");
        }
    }

    #[test]
    fn a_step_after_a_planned_wait_waits_for_its_time_one_straight_on_may_start_a_tick_early() {
        let step = |to: Vec2, leave_s: f32, arrive_s: f32| Step { to, leave_s, arrive_s, gait: Gait::Walk };
        let a = Vec2::new(1.0, 0.0);
        let b = Vec2::new(2.0, 0.0);
        let c = Vec2::new(3.0, 0.0);
        // To a at once; wait there until 3 s; then to b and straight on to c.
        let way =
            Way { steps: vec![step(a, 0.0, 1.0), step(b, 3.0, 4.0), step(c, 4.0, 5.0)], arrives: true, seen_s: 0.0 };
        let mut timed = Timed::new(way, 10.0, c);
        assert_eq!(timed.order(10.0, Vec2::ZERO), Order::Go(a, Gait::Walk));
        assert_eq!(timed.order(10.6, a), Order::Hold, "at a early: the wait is kept to its time");
        assert_eq!(timed.order(12.9, a), Order::Hold);
        assert_eq!(timed.order(13.0, a), Order::Go(b, Gait::Walk));
        assert_eq!(timed.order(13.8, b), Order::Go(c, Gait::Walk), "straight on from b a tick early");
        assert_eq!(timed.order(14.2, c - Vec2::Y), Order::Go(c, Gait::Walk), "not there yet: on to it");
        assert_eq!(timed.order(15.0, c), Order::Hold, "done: stay");
    }

    #[test]
    fn a_plan_made_with_no_guard_about_is_seen_ahead_once_one_comes() {
        let m = Museum::new();
        let (from, goal) = (Vec2::new(12.0, 16.0), Vec2::new(22.0, 16.0));
        let way = plan(&m.grid, &m.forecast(&[], from), &m.walls, from, goal, 1.0).expect("a way");
        let timed = Timed::new(way, 0.0, goal);
        assert!(!timed.seen_ahead(&m.forecast(&[], from), &m.walls, 0.0, from));
        let clara = guard(CLARA, Vec2::new(17.0, 19.0), -std::f32::consts::FRAC_PI_2);
        assert!(timed.seen_ahead(&m.forecast(&[clara], from), &m.walls, 0.0, from), "Clara looks down the way");
    }

    #[test]
    fn vive_never_stands_up_in_a_guards_plain_sight_whatever_the_plan_says() {
        let m = Museum::new();
        let clara = guard(CLARA, Vec2::new(17.0, 19.0), -std::f32::consts::FRAC_PI_2);
        let f = m.forecast(&[clara], Vec2::ZERO);
        let (close, far) = (Vec2::new(17.0, 16.0), Vec2::new(17.0, 19.0 - m.tuning.sight_range - 2.0));
        assert_eq!(safe_gait(&f, &m.walls, close, Gait::Walk), Gait::Crouch);
        assert_eq!(safe_gait(&f, &m.walls, close, Gait::Run), Gait::Crouch);
        assert_eq!(safe_gait(&f, &m.walls, far, Gait::Walk), Gait::Walk, "out of her sight it walks");
        assert_eq!(safe_gait(&f, &m.walls, far, Gait::Crouch), Gait::Crouch);
    }

    #[test]
    fn the_forecast_grades_a_spot_in_plain_sight_apart_from_one_only_within_the_margins() {
        let m = Museum::new();
        let clara = guard(CLARA, Vec2::new(17.0, 19.0), -std::f32::consts::FRAC_PI_2);
        let f = m.forecast(&[clara], Vec2::ZERO);
        let now = f.moment(0.0);
        let range = m.tuning.sight_range;
        assert_eq!(f.sighting(&now, Vec2::new(17.0, 19.0 - range + 0.5), false, &m.walls), Sighting::Seen);
        assert_eq!(f.sighting(&now, Vec2::new(17.0, 19.0 - range - 0.5), false, &m.walls), Sighting::Margin);
        assert_eq!(f.sighting(&now, Vec2::new(17.0, 19.0 - range - 2.0), false, &m.walls), Sighting::Unseen);
        assert_eq!(
            f.sighting(&now, Vec2::new(17.0, 19.0 - range + 0.5), true, &m.walls),
            Sighting::Unseen,
            "crouching"
        );
    }
}
