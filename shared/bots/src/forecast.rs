//! Where guards will be and look in the next seconds, from their public patrol routes (the level's, or
//! the ones the alarm switches them to: `heist_shared::level::patrol::alert_route`).
//!
//! A patrolling guard walks its round at patrol speed, through the doors, turning as the rules say; the
//! bot replays that walk ahead of time. A returning guard walks back to the nearest waypoint of his
//! round first; an investigating one walks to the latest noise the bot made that he can hear and looks
//! round there, a searching one goes round the spots the radio call gave him; both then go back to
//! their rounds. A guard coming to look at glass nobody has reported yet will find the case and radio:
//! the guards on their rounds within range then come to search round it after the radio's delay, as
//! the server sends them. Any other (staring, chasing, investigating something else) is unpredictable:
//! the bot treats him as coming at it and looking every way. A spot is graded ([`Sighting`]): in a
//! guard's published sight, only within the bot's caution margins, or unseen.

use glam::Vec2;
use heist_shared::level::{NavGraph, WallSet, patrol};
use heist_shared::protocol::{GuardAlert, GuardId, GuardView};
use heist_shared::rules::{self, GUARD_TURN_RATE, GuardTuning, LOOK_AROUND_S, SEARCH_LOOK_S, about_turn};

/// The bot's caution on top of the guards' published sight range, metres.
const RANGE_MARGIN: f32 = 1.0;
/// The bot's caution on top of the guards' published half-angle of view, radians.
const ANGLE_MARGIN: f32 = 0.25;
/// The bot's caution on top of the guards' all-round noticing radius, metres.
const ALL_ROUND_MARGIN: f32 = 1.0;
/// A spot is worth stopping at (a harbour) when it stays unseen this long, seconds: long enough for
/// the guards nearby to walk past and turn round.
pub const HARBOUR_HOLD_S: f32 = 10.0;
/// Seconds between the moments a forecast checks along a walk or a hold (a quarter second: a guard turns
/// or walks little in between).
const CHECK_EVERY_S: f32 = 0.25;
/// An alerted guard (unpredictable) is assumed to come at the bot this long, seconds, then stay.
const ALERT_APPROACH_S: f32 = 5.0;

/// What any player knows of the guards: their published numbers on the session's difficulty, the
/// museum's doors (they walk through them), each one's round now (by guard id, its waypoints) and the
/// alarm level.
#[derive(Clone, Copy)]
pub struct Known<'a> {
    /// The guards' numbers.
    pub tuning: &'a GuardTuning,
    /// The room graph.
    pub nav: &'a NavGraph,
    /// Each guard's round now.
    pub routes: &'a [Vec<Vec2>],
    /// The alarm level.
    pub alarm: u8,
}

/// A noise the bot made: where, when (the bot's clock) and how loud (its audible radius, metres, as in
/// `heist_shared::rules`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Where.
    pub at: Vec2,
    /// When, seconds on the bot's clock.
    pub when_s: f32,
    /// Its audible radius, metres.
    pub loudness: f32,
    /// Broken glass no guard has reported yet: the guard who comes to look at it will find the case
    /// and radio the others to search round it (`rules::EVIDENCE_SPOTS`).
    pub evidence: bool,
}

/// What the bot heard: the noises it made lately (a guard who comes to look comes to one of them) and
/// the search spots radio calls gave each guard (by guard id).
#[derive(Clone, Copy, Default)]
pub struct Heard<'a> {
    /// The noises the bot made lately, oldest first.
    pub noises: &'a [Noise],
    /// The spots each radioed guard has still to search.
    pub searches: &'a [(GuardId, Vec<Vec2>)],
}

/// One guard's future.
enum Future {
    /// Walks `lead` first (back to his round, through the doors, at `lead_speed`), then the route
    /// (through the doors, as the guard walks it) from waypoint `next` on, at `speed`; faces `facing`
    /// now (he may still be turning).
    Patrol { lead: Vec<Vec2>, lead_speed: f32, route: Vec<Vec2>, next: usize, start: Vec2, facing: f32, speed: f32 },
    /// Walks `path` (through the doors) at `speed` from `start`, looking where he walks, stopping at
    /// each point its pause to look every way (an investigating guard going to a noise the bot made,
    /// a searching one going round the spots the radio gave him); then goes back to his round
    /// (`then`), or stays at the end for good when his round is not known.
    Goes { path: Vec<(Vec2, f32)>, start: Vec2, facing: f32, speed: f32, then: Option<Box<Future>> },
    /// Unpredictable: assumed to walk straight at the bot, looking all round.
    Alert(Vec2, Vec2),
    /// `before` until `switch_s`, then `after` (from where `before` left him): a guard who will hear
    /// a radio call the bot expects.
    Later { before: Box<Future>, switch_s: f32, after: Box<Future> },
}

/// How well a spot would be seen, worst first last.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Sighting {
    /// No guard would see it.
    Unseen,
    /// Only within the bot's caution margins (a guard a little off where the forecast has him).
    Margin,
    /// Within a guard's published sight.
    Seen,
}

/// Where every guard is and looks (`None`: every way) at one moment of a forecast.
#[derive(Debug)]
pub struct Moment(Vec<(Vec2, Option<f32>)>);

/// The forecast of every guard.
pub struct Forecast {
    futures: Vec<Future>,
    alarm: u8,
    tuning: GuardTuning,
}

fn angle_of(v: Vec2) -> f32 {
    v.y.atan2(v.x)
}

fn wrap(a: f32) -> f32 {
    (a + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI
}

/// Leg `i` of the closed `route` (from waypoint `i` to the next) and how far `p` is from it.
fn leg(route: &[Vec2], i: usize, p: Vec2) -> (Vec2, Vec2, f32) {
    let (a, b) = (route[i], route[(i + 1) % route.len()]);
    let ab = b - a;
    let along = ((p - a).dot(ab) / ab.length_squared().max(1e-6)).clamp(0.0, 1.0);
    (a, b, p.distance(a + ab * along))
}

/// The waypoint a guard at `p` facing `facing` walks to: the far end (in the facing's direction) of
/// the route's leg nearest to it.
fn next_waypoint(route: &[Vec2], p: Vec2, facing: f32) -> usize {
    let n = route.len();
    let ahead = Vec2::from_angle(facing);
    let nearest = (0..n)
        .map(|i| {
            let (a, b, d) = leg(route, i, p);
            // Legs walked the other way are a last resort (the guard may be mid-turn).
            let against = if (b - a).dot(ahead) < 0.0 { 0.5 } else { 0.0 };
            (d + against, i)
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .map_or(0, |(_, i)| i);
    let (a, b, _) = leg(route, nearest, p);
    if (b - a).dot(ahead) >= 0.0 && p.distance(b) > 0.3 { (nearest + 1) % n } else { nearest }
}

/// Where a guard who began turning from `from` towards `to` `turning_s` seconds ago looks now: guards
/// turn at [`GUARD_TURN_RATE`], the short way round, about-turns to their left ([`about_turn`]).
fn turning_facing(from: f32, to: f32, turning_s: f32) -> f32 {
    let diff = about_turn(wrap(to - from));
    let swept = GUARD_TURN_RATE * turning_s;
    if swept >= diff.abs() { to } else { wrap(from + diff.signum() * swept) }
}

/// A guard farther than this from every leg of his round is off it (coming back to it), metres.
const OFF_ROUTE_M: f32 = 0.75;

/// The round through `waypoints` as a guard walks it, from each to the next through the doors between
/// (the room graph's route, as the server's guards take it), and where each waypoint is in it.
fn walked(nav: &NavGraph, waypoints: &[Vec2]) -> (Vec<Vec2>, Vec<usize>) {
    let n = waypoints.len();
    let (mut points, mut at) = (vec![waypoints[0]], vec![0]);
    for i in 0..n {
        let (a, b) = (waypoints[i], waypoints[(i + 1) % n]);
        let mut leg = nav.route(a, b).unwrap_or_else(|| vec![b]);
        if i + 1 == n {
            leg.pop(); // back at the first waypoint
        } else {
            at.push(points.len() + leg.len() - 1);
        }
        points.extend(leg);
    }
    (points, at)
}

/// How far `p` is from the nearest leg of `route`, metres.
fn off_route(route: &[Vec2], p: Vec2) -> f32 {
    (0..route.len()).map(|i| leg(route, i, p).2).fold(f32::INFINITY, f32::min)
}

impl Forecast {
    /// Builds the forecast of `guards` (those in sight and those imagined) from what any player knows
    /// (`known`) and what the bot heard (`heard`); `me` is the bot's position.
    pub fn new(known: &Known<'_>, guards: &[&GuardView], me: Vec2, heard: &Heard<'_>) -> Self {
        let built: Vec<(Future, Option<(Vec2, f32)>)> = guards.iter().map(|g| future(known, g, me, heard)).collect();
        let callers: Vec<(usize, Vec2, f32)> =
            built.iter().enumerate().filter_map(|(i, (_, call))| call.map(|(at, when)| (i, at, when))).collect();
        let mut forecast =
            Self { futures: built.into_iter().map(|(f, _)| f).collect(), alarm: known.alarm, tuning: *known.tuning };
        forecast.expect_evidence_calls(known, guards, me, &callers);
        forecast
    }

    /// The guards who will hear the radio calls `callers` make (guard, broken case found, seconds from
    /// now) come to search round it after the radio's delay, as the server sends them: those on their
    /// rounds within the radio's range of the caller then, nearest to the case first, each his share of
    /// [`rules::EVIDENCE_SPOTS`] spots (`patrol::orders`). One call per guard, the earliest.
    fn expect_evidence_calls(
        &mut self,
        known: &Known<'_>,
        guards: &[&GuardView],
        me: Vec2,
        callers: &[(usize, Vec2, f32)],
    ) {
        let t = known.tuning;
        if t.radio_range_m <= 0.0 {
            return;
        }
        let mut callers = callers.to_vec();
        callers.sort_by(|a, b| a.2.total_cmp(&b.2));
        let mut answered = vec![false; guards.len()];
        let mut switches = Vec::new();
        for &(caller, at, when) in &callers {
            let calm = |j: usize| matches!(self.futures[j], Future::Patrol { .. });
            let mut answering: Vec<(usize, Vec2)> = (0..guards.len())
                .filter(|&j| j != caller && !answered[j] && calm(j))
                .map(|j| (j, self.pose(j, when).0))
                .filter(|(_, p)| p.distance(at) <= t.radio_range_m)
                .collect();
            answering.sort_by(|a, b| a.1.distance(at).total_cmp(&b.1.distance(at)));
            let heard_s = when + t.radio_delay_s;
            let orders = patrol::orders(known.nav, at, rules::EVIDENCE_SPOTS, answering.len());
            for (&(j, _), spots) in answering.iter().zip(orders) {
                answered[j] = true;
                let (position, facing) = self.pose(j, heard_s);
                let g = guards[j];
                let searching = GuardView {
                    position,
                    facing: facing.unwrap_or(g.facing),
                    alert: GuardAlert::Searching,
                    ..g.clone()
                };
                let searches = [(g.id, spots)];
                let (after, _) = future(known, &searching, me, &Heard { noises: &[], searches: &searches });
                switches.push((j, heard_s, after));
            }
        }
        for (j, switch_s, after) in switches {
            let before = std::mem::replace(&mut self.futures[j], Future::Alert(me, me));
            self.futures[j] = Future::Later { before: Box::new(before), switch_s, after: Box::new(after) };
        }
    }

    /// Where a guard last seen as `last`, `ago_s` seconds ago, is likely now (what a player who lost
    /// sight of it would guess): walked on along its route if it was patrolling; where it was if it was
    /// alerted, for `alert_memory_s`, and after that back on its patrol from there.
    pub fn imagine(known: &Known<'_>, last: &GuardView, ago_s: f32, alert_memory_s: f32) -> GuardView {
        if last.alert != GuardAlert::Patrolling && ago_s < alert_memory_s {
            return last.clone();
        }
        let calm = GuardView { alert: GuardAlert::Patrolling, ..last.clone() };
        let ago_s = if last.alert == GuardAlert::Patrolling { ago_s } else { ago_s - alert_memory_s };
        let forecast = Self::new(known, &[&calm], last.position, &Heard::default());
        match forecast.futures.first() {
            Some(Future::Patrol { .. }) => {
                let (position, facing) = forecast.pose(0, ago_s);
                GuardView { position, facing: facing.unwrap_or(last.facing), ..calm }
            }
            _ => calm,
        }
    }

    /// Pose (position, facing) of guard `i` after `t` seconds.
    fn pose(&self, i: usize, t: f32) -> (Vec2, Option<f32>) {
        self.pose_of(&self.futures[i], t)
    }

    /// Pose (position, facing; `None`: every way) of a guard with `future` after `t` seconds.
    fn pose_of(&self, future: &Future, t: f32) -> (Vec2, Option<f32>) {
        match future {
            Future::Alert(p, towards) => {
                let d = *towards - *p;
                let walk = (self.tuning.investigate_speed * t.min(ALERT_APPROACH_S)).min((d.length() - 1.0).max(0.0));
                (*p + d.normalize_or_zero() * walk, None)
            }
            Future::Later { before, switch_s, after } => {
                if t < *switch_s {
                    self.pose_of(before, t)
                } else {
                    self.pose_of(after, t - switch_s)
                }
            }
            Future::Goes { path, start, facing, speed, then } => {
                let (mut at, mut left) = (*start, t);
                for (i, &(wp, pause)) in path.iter().enumerate() {
                    let d = at.distance(wp);
                    if d >= left * speed {
                        let dir = (wp - at).normalize_or_zero();
                        // Turning from where he looked towards the way first (the first leg).
                        let look = |h: f32| if i == 0 { turning_facing(*facing, h, t) } else { h };
                        return (at + dir * left * speed, (dir != Vec2::ZERO).then(|| look(angle_of(dir))));
                    }
                    left -= d / speed.max(1e-3) + pause;
                    at = wp;
                    if left <= 0.0 {
                        return (at, None); // looking round there
                    }
                }
                match then {
                    Some(then) => self.pose_of(then, left),
                    None => (at, None),
                }
            }
            Future::Patrol { lead, lead_speed, route, next, start, facing, speed } => {
                let n = route.len();
                let target_at = |k: usize| if k < lead.len() { lead[k] } else { route[(next + k - lead.len()) % n] };
                let lead_length: f32 = std::iter::once(*start)
                    .chain(lead.iter().copied())
                    .zip(lead.iter().copied().chain(std::iter::once(route[*next])))
                    .map(|(a, b)| a.distance(b))
                    .sum();
                // Distance walked in `t`: the way back at `lead_speed`, then the round at `speed`.
                let lead_s = lead_length / lead_speed.max(1e-3);
                let mut left = if lead.is_empty() || t <= lead_s {
                    t * if lead.is_empty() { *speed } else { *lead_speed }
                } else {
                    lead_length + (t - lead_s) * speed
                };
                let (mut at, mut k) = (*start, 0);
                // The facing the guard turns from, and the distance walked when that turn began.
                let (mut turned_from, mut turn_at) = (*facing, 0.0);
                let mut heading: Option<f32> = None;
                let mut walked = 0.0;
                for _ in 0..=4 * (n + lead.len()) {
                    let to = target_at(k) - at;
                    let d = to.length();
                    if d > 1e-4 {
                        let new = angle_of(to);
                        if let Some(old) = heading
                            && wrap(new - old).abs() > 1e-3
                        {
                            (turned_from, turn_at) = (old, walked);
                        }
                        heading = Some(new);
                    }
                    if d >= left {
                        at += to.normalize_or_zero() * left;
                        walked += left;
                        break;
                    }
                    left -= d;
                    walked += d;
                    at = target_at(k);
                    k += 1;
                }
                let turning_s = (walked - turn_at) / speed.max(1e-3);
                (at, heading.map(|h| turning_facing(turned_from, h, turning_s)))
            }
        }
    }

    /// Where every guard is and looks `t` seconds from now.
    pub fn moment(&self, t: f32) -> Moment {
        Moment((0..self.futures.len()).map(|i| self.pose(i, t)).collect())
    }

    /// True when some guard at `moment` could see a person at `p` (crouching or not).
    pub fn sees(&self, moment: &Moment, p: Vec2, crouching: bool, walls: &WallSet) -> bool {
        self.sighting(moment, p, crouching, walls) != Sighting::Unseen
    }

    /// How well the guards at `moment` would see a person at `p` (crouching or not): by their
    /// published numbers, or only within the bot's caution margins, or not at all.
    pub fn sighting(&self, moment: &Moment, p: Vec2, crouching: bool, walls: &WallSet) -> Sighting {
        let t_ = &self.tuning;
        let margined = GuardTuning { sight_range: t_.sight_range + RANGE_MARGIN, ..*t_ };
        let (range, sure_range) =
            (margined.sight_range_at(self.alarm, false, crouching), t_.sight_range_at(self.alarm, false, crouching));
        let (all_round, half_angle) = (t_.notice_radius + ALL_ROUND_MARGIN, t_.half_angle(false) + ANGLE_MARGIN);
        let (sure_all_round, sure_half_angle) = (t_.notice_radius, t_.half_angle(false));
        let mut worst = Sighting::Unseen;
        for &(g, facing) in &moment.0 {
            let d = p - g;
            let dist = d.length();
            let off = facing.map_or(0.0, |f| wrap(angle_of(d) - f).abs());
            let grade = if dist < sure_all_round || (dist < sure_range && off < sure_half_angle) {
                Sighting::Seen
            } else if dist < all_round || (dist < range && off < half_angle) {
                Sighting::Margin
            } else {
                continue;
            };
            if grade > worst && walls.line_of_sight(g, p) {
                worst = grade;
            }
        }
        worst
    }

    /// True when some guard at `moment` could hear Vive running at `p` (straight-line distance, with the
    /// same caution as the bot's run check: half as far again as the published radius).
    pub fn hears_running(&self, moment: &Moment, p: Vec2) -> bool {
        let radius = rules::RUN_LOUDNESS * self.tuning.hearing_at(self.alarm) * 1.5;
        moment.0.iter().any(|&(g, _)| g.distance(p) < radius)
    }

    /// True when some guard could see a person at `p` (crouching or not) `t` seconds from now.
    pub fn seen(&self, p: Vec2, t: f32, crouching: bool, walls: &WallSet) -> bool {
        self.sees(&self.moment(t), p, crouching, walls)
    }

    /// True when `p` stays unseen (crouching) for the next `horizon` seconds.
    pub fn hidden_for(&self, p: Vec2, horizon: f32, walls: &WallSet) -> bool {
        self.holdable_for(p, 0.0, horizon, walls)
    }

    /// True when a crouching Vive at `p` from `t` seconds on stays unseen for `hold` seconds more.
    fn holdable_for(&self, p: Vec2, t: f32, hold: f32, walls: &WallSet) -> bool {
        (0..=(hold / CHECK_EVERY_S) as usize).all(|k| !self.seen(p, t + k as f32 * CHECK_EVERY_S, true, walls))
    }

    /// Walks the polyline from `from` through `path` at `speed` (crouching or not; a step every
    /// [`CHECK_EVERY_S`]), `until` seconds at most, asking `stop` at each step (where, when).
    fn walk(
        &self,
        from: Vec2,
        path: &[Vec2],
        (speed, crouching): (f32, bool),
        until: f32,
        walls: &WallSet,
        mut stop: impl FnMut(Vec2, f32) -> bool,
    ) -> Walk {
        let (mut at, mut t, step) = (from, 0.0, CHECK_EVERY_S);
        for &wp in path {
            while at.distance(wp) > 1e-3 {
                if self.seen(at, t, crouching, walls) {
                    return Walk::Seen;
                }
                if stop(at, t) {
                    return Walk::Stopped;
                }
                if t >= until {
                    return Walk::OutOfTime;
                }
                let d = (wp - at).length().min(speed * step);
                at += (wp - at).normalize_or_zero() * d;
                t += step;
            }
        }
        Walk::Arrived(at, t)
    }

    /// True when the whole walk from `from` through `path` at `speed` stays unseen and its end then
    /// stays unseen for [`HARBOUR_HOLD_S`] (a hiding place worth going to).
    pub fn hiding_place(&self, from: Vec2, path: &[Vec2], speed: f32, crouching: bool, walls: &WallSet) -> bool {
        match self.walk(from, path, (speed, crouching), 60.0, walls, |_, _| false) {
            Walk::Arrived(at, t) => self.holdable_for(at, t, HARBOUR_HOLD_S, walls),
            _ => false,
        }
    }
}

/// How a forecast walk ended.
enum Walk {
    /// A guard would see the walker.
    Seen,
    /// The caller's stop condition held.
    Stopped,
    /// Time ran out on the way.
    OutOfTime,
    /// At the end of the path (where, when).
    Arrived(Vec2, f32),
}

/// The future of guard `g` (see [`Forecast::new`]), and, when he is coming to look at broken glass no
/// guard has reported yet, the call he will make there: (the case, seconds from now).
fn future(known: &Known<'_>, g: &GuardView, me: Vec2, heard: &Heard<'_>) -> (Future, Option<(Vec2, f32)>) {
    let Known { tuning, nav, routes, alarm } = *known;
    let (patrol_speed, hurry) =
        (tuning.hasted(tuning.patrol_speed, alarm), tuning.hasted(tuning.investigate_speed, alarm));
    let waypoints = routes.get(usize::from(g.id.0)).map_or(&[][..], |r| &r[..]);
    // Back from `from` to the nearest waypoint of his round, then on along it (as the
    // server's guards do), or along it from where he is if he is on it.
    let round = |from: Vec2, facing: f32, on_it: bool| {
        if waypoints.len() < 2 {
            return None;
        }
        let (route, at) = walked(nav, waypoints);
        let (speed, lead_speed) = (patrol_speed, hurry);
        if on_it && off_route(&route, from) < OFF_ROUTE_M {
            let next = next_waypoint(&route, from, facing);
            return Some(Future::Patrol { lead: Vec::new(), lead_speed, route, next, start: from, facing, speed });
        }
        let k = (0..waypoints.len())
            .min_by(|&a, &b| from.distance(waypoints[a]).total_cmp(&from.distance(waypoints[b])))
            .unwrap_or(0);
        let mut lead = nav.route(from, waypoints[k]).unwrap_or_default();
        lead.pop();
        Some(Future::Patrol { lead, lead_speed, route, next: at[k], start: from, facing, speed })
    };
    let goes = |mut path: Vec<(Vec2, f32)>| {
        // A guard stops to look round as soon as he is within [`rules::ARRIVED_M`] of the
        // spot, short of it on his way there.
        for i in 0..path.len() {
            if path[i].1 > 0.0 {
                let before = if i == 0 { g.position } else { path[i - 1].0 };
                let back = (before - path[i].0).clamp_length_max(rules::ARRIVED_M - 0.1);
                path[i].0 += back;
            }
        }
        let end = path.last().map_or(g.position, |p| p.0);
        let then = round(end, g.facing, false).map(Box::new);
        Future::Goes { path, start: g.position, facing: g.facing, speed: hurry, then }
    };
    if g.alert == GuardAlert::Searching
        && let Some((_, spots)) = heard.searches.iter().find(|(id, _)| *id == g.id)
    {
        // Radioed to search these spots: through the doors to each, looking round there.
        let mut path = Vec::new();
        let mut from = g.position;
        for &spot in spots {
            path.extend(nav.route(from, spot).unwrap_or_else(|| vec![spot]).into_iter().map(|p| (p, 0.0)));
            if let Some(last) = path.last_mut() {
                last.1 = SEARCH_LOOK_S;
            }
            from = spot;
        }
        return (goes(path), None);
    }
    if g.alert == GuardAlert::Investigating {
        // Coming to look at a noise the bot made: the latest he can hear from where he is
        // (a guard goes to the last noise he heard), else the nearest by the doors, if any.
        let hearing = tuning.hearing_at(alarm);
        let latest_heard =
            heard.noises.iter().rev().find(|n| nav.heard_margin(n.at, g.position, n.loudness * hearing) >= 0.0);
        let nearest = || {
            heard
                .noises
                .iter()
                .map(|n| (nav.route_length(g.position, n.at), n))
                .filter(|(d, _)| d.is_finite())
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, n)| n)
        };
        let noise = latest_heard.or_else(nearest);
        if let Some((noise, route)) = noise.and_then(|n| Some((n, nav.route(g.position, n.at)?))) {
            // He finds the case (and radios) as he gets there.
            let call = noise.evidence.then(|| (noise.at, NavGraph::path_length(g.position, &route) / hurry));
            let mut path: Vec<(Vec2, f32)> = route.into_iter().map(|p| (p, 0.0)).collect();
            if let Some(last) = path.last_mut() {
                last.1 = LOOK_AROUND_S;
            }
            return (goes(path), call);
        }
    }
    let calm = matches!(g.alert, GuardAlert::Patrolling | GuardAlert::Returning);
    match round(g.position, g.facing, g.alert == GuardAlert::Patrolling) {
        Some(future) if calm => (future, None),
        _ => (Future::Alert(g.position, me), None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::level::Level;
    use heist_shared::rules::ARRIVED_M;
    use std::f32::consts::{FRAC_PI_2, PI};

    const BRUNO: usize = 0;
    const CLARA: usize = 1;
    const DMITRI: usize = 2;

    struct Museum {
        level: Level,
        nav: NavGraph,
        walls: WallSet,
        routes: Vec<Vec<Vec2>>,
        tuning: GuardTuning,
    }

    impl Museum {
        fn new() -> Self {
            let level = Level::museum();
            let routes = level.guards.iter().map(|g| g.route.clone()).collect();
            Self {
                nav: NavGraph::new(&level),
                walls: WallSet::new(&level),
                routes,
                level,
                tuning: GuardTuning::default(),
            }
        }

        fn known(&self) -> Known<'_> {
            Known { tuning: &self.tuning, nav: &self.nav, routes: &self.routes, alarm: 0 }
        }

        fn forecast(&self, g: &GuardView, heard: &Heard<'_>) -> Forecast {
            Forecast::new(&self.known(), &[g], Vec2::ZERO, heard)
        }
    }

    fn guard(id: usize, at: Vec2, facing: f32, alert: GuardAlert) -> GuardView {
        GuardView { id: GuardId(id as u16), name: format!("G{id}"), position: at, facing, alert }
    }

    #[test]
    fn a_patrolling_guard_is_replayed_along_its_route() {
        let m = Museum::new();
        let route = &m.routes[BRUNO];
        let f = m.forecast(&guard(BRUNO, route[0], 0.0, GuardAlert::Patrolling), &Heard::default());
        let (p, facing) = f.pose(0, 2.0);
        assert!((p - (route[0] + (route[1] - route[0]).normalize() * 2.2)).length() < 1e-3, "{p:?}");
        assert_eq!(facing, Some(0.0));
    }

    #[test]
    fn a_spot_behind_a_walking_guard_is_hidden_but_one_ahead_is_not() {
        let m = Museum::new();
        let g = guard(BRUNO, m.routes[BRUNO][0] + Vec2::new(4.0, 0.0), 0.0, GuardAlert::Patrolling);
        let f = m.forecast(&g, &Heard::default());
        assert!(f.seen(g.position + Vec2::new(4.0, 0.0), 0.0, false, &m.walls));
        assert!(!f.seen(g.position - Vec2::new(4.0, 0.0), 0.0, false, &m.walls));
    }

    #[test]
    fn a_guard_at_the_end_of_his_round_sweeps_his_look_round_to_his_left_as_the_server_turns_him() {
        let m = Museum::new();
        let end = m.routes[BRUNO][1]; // (35, 5), walking +x towards it
        let f = m.forecast(&guard(BRUNO, end - Vec2::new(1.1, 0.0), 0.0, GuardAlert::Patrolling), &Heard::default());
        // One second to the end; a quarter turn (π/2 at 4 rad/s: 0.39 s) later he looks +z, his left.
        let (_, facing) = f.pose(0, 1.0 + FRAC_PI_2 / GUARD_TURN_RATE);
        assert!(wrap(facing.expect("walking") - FRAC_PI_2).abs() < 0.05, "{facing:?}");
        let (_, facing) = f.pose(0, 1.0 + PI / GUARD_TURN_RATE + 0.1);
        assert!(wrap(facing.expect("walking") - PI).abs() < 1e-3, "turned about: {facing:?}");
        // So a spot on his left just past the end is seen mid-turn, one on his right is not.
        let (left, right) = (end + Vec2::new(0.0, 3.0), end - Vec2::new(0.0, 3.0));
        let mid_turn = 1.0 + FRAC_PI_2 / GUARD_TURN_RATE;
        assert!(f.seen(left, mid_turn, false, &m.walls) && !f.seen(right, mid_turn, false, &m.walls));
        assert_eq!(about_turn(-PI + 0.01), PI + 0.01, "the rule the server turns by");
    }

    #[test]
    fn a_round_through_another_room_is_walked_through_the_doors_between() {
        let m = Museum::new();
        let treasury = m.nav.room_centre(m.level.room_index("treasury").expect("room")).expect("centre");
        let waypoints = vec![Vec2::new(17.0, 13.5), treasury]; // sculpture hall, then the treasury
        let (route, at) = walked(&m.nav, &waypoints);
        assert_eq!(route[at[1]], treasury);
        let door = Vec2::new(24.0, 16.0);
        assert!(route.iter().any(|p| p.distance(door) < 1.0), "through the door: {route:?}");
        assert!(route.iter().all(|p| m.nav.room_at(*p).is_some()), "never through a wall: {route:?}");
    }

    #[test]
    fn a_returning_guard_walks_back_to_his_nearest_waypoint_through_the_doors() {
        let m = Museum::new();
        // Clara, back from a search in the west gallery, returns to her round in the sculpture hall
        // through the closed door at (17, 10), not through the wall.
        let g = guard(CLARA, Vec2::new(13.4, 1.9), 0.0, GuardAlert::Returning);
        let f = m.forecast(&g, &Heard::default());
        let speed = m.tuning.investigate_speed;
        let door = Vec2::new(17.0, 10.0);
        let to_door = m.nav.route_length(g.position, door) / speed;
        let (p, _) = f.pose(0, to_door);
        assert!(p.distance(door) < 1.0, "at the door after {to_door} s: {p:?}");
        let (later, _) = f.pose(0, to_door + 10.0);
        assert!(m.nav.room_at(later) == m.level.room_index("sculpture_hall"), "back on the round: {later:?}");
    }

    #[test]
    fn an_investigating_guard_comes_to_the_noise_the_bot_made_and_looks_round_there() {
        let m = Museum::new();
        let glass = Vec2::new(21.0, 1.2);
        let g = guard(BRUNO, Vec2::new(30.0, 5.0), 0.0, GuardAlert::Investigating);
        let noise = Noise { at: glass, when_s: 0.0, loudness: rules::GLASS_LOUDNESS, evidence: false };
        let f = m.forecast(&g, &Heard { noises: &[noise], searches: &[] });
        let (p, facing) = f.pose(0, 2.0);
        assert!(p.x < 30.0 - 2.0, "walks towards the glass: {p:?}");
        assert!(facing.is_some(), "looking where he goes");
        // He stops to look round as soon as he is within reach of it (as the server's guards do), for
        // LOOK_AROUND_S, then goes back to his round.
        let speed = m.tuning.investigate_speed;
        let arrives = (m.nav.route_length(g.position, glass) - (ARRIVED_M - 0.1)) / speed;
        let (there, look) = f.pose(0, arrives + 0.5 * LOOK_AROUND_S);
        assert!(there.distance(glass) < ARRIVED_M && look.is_none(), "looks round at the glass: {there:?}");
        let (back, look) = f.pose(0, arrives + LOOK_AROUND_S + 1.0);
        assert!(back.distance(there) > 0.5 && look.is_some(), "then walks back to his round: {back:?}");
        let unknown = m.forecast(&g, &Heard::default());
        assert!(unknown.pose(0, 2.0).1.is_none(), "without a noise he is unpredictable: looks every way");
    }

    #[test]
    fn an_investigating_guard_comes_to_the_latest_noise_he_heard_not_an_older_nearer_one() {
        let m = Museum::new();
        // A prop thrown by him a while ago, then glass broken down the gallery: he goes to the glass.
        let (thud, glass) = (Vec2::new(27.0, 6.0), Vec2::new(21.0, 1.2));
        let g = guard(BRUNO, Vec2::new(30.0, 5.0), 0.0, GuardAlert::Investigating);
        let noises = [
            Noise { at: thud, when_s: 0.0, loudness: rules::THUD_LOUDNESS, evidence: false },
            Noise { at: glass, when_s: 5.0, loudness: rules::GLASS_LOUDNESS, evidence: true },
        ];
        let f = m.forecast(&g, &Heard { noises: &noises, searches: &[] });
        let arrives = m.nav.route_length(g.position, glass) / m.tuning.investigate_speed;
        let (there, _) = f.pose(0, arrives);
        assert!(there.distance(glass) < ARRIVED_M, "at the glass when he would be: {there:?}");
        // A noise he cannot hear from where he is (a thud far off behind closed doors) is not his.
        let far = Noise { at: Vec2::new(2.0, 14.0), when_s: 6.0, loudness: rules::THUD_LOUDNESS, evidence: false };
        assert!(m.nav.heard_margin(far.at, g.position, far.loudness) < 0.0);
        let noises = [noises[1], far];
        let f = m.forecast(&g, &Heard { noises: &noises, searches: &[] });
        assert!(f.pose(0, arrives).0.distance(glass) < ARRIVED_M, "still the glass");
    }

    #[test]
    fn a_searching_guard_goes_round_the_spots_the_radio_gave_him_looking_round_at_each() {
        let m = Museum::new();
        let (a, b) = (Vec2::new(20.0, 5.0), Vec2::new(31.0, 5.0));
        let g = guard(BRUNO, Vec2::new(15.0, 5.0), 0.0, GuardAlert::Searching);
        let searches = [(GuardId(BRUNO as u16), vec![a, b])];
        let f = m.forecast(&g, &Heard { noises: &[], searches: &searches });
        let speed = m.tuning.investigate_speed;
        // He stops to look round within reach of each spot, short of it.
        let short = ARRIVED_M - 0.1;
        let at_a = (5.0 - short) / speed;
        assert!(f.pose(0, at_a + 0.5 * SEARCH_LOOK_S).0.distance(a) < ARRIVED_M, "looks round at the first spot");
        assert!(f.pose(0, at_a + 0.5 * SEARCH_LOOK_S).1.is_none());
        let (p, facing) = f.pose(0, at_a + SEARCH_LOOK_S + 1.0);
        assert!((p.x - (20.0 - short + speed)).abs() < 1e-3 && facing == Some(0.0), "then on to the next: {p:?}");
        let (last, look) = f.pose(0, at_a + SEARCH_LOOK_S + (b.x - a.x) / speed + SEARCH_LOOK_S + 3.0);
        assert!(last.distance(b) > ARRIVED_M && look.is_some(), "after the last, back to his round: {last:?}");
    }

    #[test]
    fn a_guard_coming_to_unreported_glass_radios_there_and_the_guards_in_range_come_to_search_round_it() {
        let m = Museum::new();
        let case = Vec2::new(28.0, 20.8);
        let clara = guard(CLARA, Vec2::new(18.0, 15.5), 0.0, GuardAlert::Investigating);
        let dmitri = guard(DMITRI, m.routes[DMITRI][1], std::f32::consts::FRAC_PI_2, GuardAlert::Patrolling);
        let glass = |evidence| [Noise { at: case, when_s: 0.0, loudness: rules::GLASS_LOUDNESS, evidence }];
        let forecast = |noises: &[Noise], tuning: &GuardTuning| {
            let known = Known { tuning, ..m.known() };
            Forecast::new(&known, &[&clara, &dmitri], Vec2::ZERO, &Heard { noises, searches: &[] })
        };
        let (reported, unreported) = (forecast(&glass(false), &m.tuning), forecast(&glass(true), &m.tuning));
        let speed = m.tuning.investigate_speed;
        let heard_s = m.nav.route_length(clara.position, case) / speed + m.tuning.radio_delay_s;
        // Until the call reaches him, Dmitri walks his round either way.
        let before = heard_s - 0.5;
        assert_eq!(unreported.pose(1, before), reported.pose(1, before));
        // Then he searches his share of the spots round the case, looking round at the first.
        let first = patrol::orders(&m.nav, case, rules::EVIDENCE_SPOTS, 1)[0][0];
        let from = unreported.pose(1, heard_s).0;
        let there = heard_s + (m.nav.route_length(from, first) - (ARRIVED_M - 0.1)) / speed + 0.5 * SEARCH_LOOK_S;
        let (p, look) = unreported.pose(1, there);
        assert!(p.distance(first) < ARRIVED_M && look.is_none(), "looks round at {first}: {p:?}");
        assert!(reported.pose(1, there).0.distance(first) > 2.0, "glass already reported: no call, no search");
        // Guards without radio (easy) never come.
        let easy = rules::Difficulty::Easy.tuning();
        let quiet = forecast(&glass(true), &easy);
        let unradioed = Forecast::new(
            &Known { tuning: &easy, ..m.known() },
            &[&clara, &dmitri],
            Vec2::ZERO,
            &Heard { noises: &glass(false), searches: &[] },
        );
        assert_eq!(quiet.pose(1, there), unradioed.pose(1, there));
    }

    #[test]
    fn a_spot_clear_now_where_a_guard_is_about_to_look_is_no_hiding_place() {
        let m = Museum::new();
        // Clara walks up and down z = 15 between x 13 and 33. Creeping to a spot on her line behind her
        // is clear while she walks away west, but the spot is no harbour: she turns at the end of her
        // round and comes back within seconds.
        let g = guard(CLARA, Vec2::new(14.0, 15.0), PI, GuardAlert::Patrolling); // walking west, to her end
        let f = m.forecast(&g, &Heard::default());
        let on_her_line = [Vec2::new(20.2, 15.0)];
        let from = Vec2::new(20.2, 17.5);
        assert!(f.hidden_for(from, 2.0, &m.walls), "here is fine for now");
        assert!(!f.hiding_place(from, &on_her_line, rules_crouch(), true, &m.walls));
    }

    fn rules_crouch() -> f32 {
        heist_shared::rules::CROUCH_SPEED
    }
}
