//! Working out the Vive bot's [`Perception`] from the view, its map and memory, and carrying a
//! [`Plan`] out as a movement and maybe an action (the routes, the hiding places and the refuges).

use glam::Vec2;
use heist_shared::protocol::{Gait, GuardAlert, ItemKind, ItemPlace, ViveMsg};
use heist_shared::rules;

use super::decide::{LURE_AFTER_S, Perception, Plan};
use super::goal::Goal;
use super::map::Map;
use super::memory::Memory;
use super::view::View;
use crate::forecast::{Forecast, HARBOUR_HOLD_S, Noise};
use crate::spacetime::{self, Order, Timed};

/// Closer than this beyond a guard's all-round noticing radius counts as exposed, seen or not (walls
/// and doors are thin), metres.
const TOO_CLOSE_M: f32 = 1.0;
/// Glass may be broken within a guard's hearing only when he needs this long to get to it, seconds
/// (time to grab the copy and get out of sight).
const BREAK_HEADSTART_S: f32 = 7.0;
/// After the last sight of a guard chasing, the bot keeps fleeing this long, seconds.
const FLEE_ON_S: f32 = 5.0;
/// Seconds a timed way that stays unseen is followed before it is made again from what the bot sees then.
const REPLAN_S: f32 = 3.0;
/// Seconds a timed way is followed at least before it is made again because it will be seen.
const QUICK_REPLAN_S: f32 = 0.25;
/// A lure lands at least this much farther from Vive than the guard it draws, metres.
const LURE_BEYOND_M: f32 = 1.0;
/// How long an item given up on stays given up, seconds.
const AVOID_FOR_S: f32 = 60.0;

/// Everything the decisions need this frame. Plans the way to the goal first (kept in memory while the
/// goal stays).
pub(crate) fn perceive(
    map: &Map,
    memory: &mut Memory,
    view: &View<'_>,
    forecast: &Forecast,
    goal: &Goal,
    reckless: bool,
) -> Perception {
    let me = view.me.position;
    let target = goal.at();
    let action = match goal {
        Goal::Go(_) => None,
        Goal::Break(_, c, _) => Some(ViveMsg::Break(*c)),
        Goal::Take(_, i) => Some(ViveMsg::PickUp(*i)),
        Goal::Deliver(_, i) => {
            let busy = view.items.iter().any(|it| it.place == ItemPlace::Workbench);
            (!busy).then_some(ViveMsg::PlaceOnWorkbench(*i))
        }
    };
    let at_goal = me.distance(target) <= rules::REACH * 0.8;
    memory.approach(target, me);
    plan_route(map, memory, view, target, reckless);
    if view.guards.iter().any(|g| g.alert == GuardAlert::Chasing) {
        memory.chased_at = Some(memory.clock_s);
    }
    let mut p = Perception {
        reckless,
        chased: memory.chased_at.is_some_and(|t| memory.clock_s - t < FLEE_ON_S),
        at_goal,
        action,
        waited_s: memory.stalled_s(),
        break_waited_s: memory.break_waited_s,
        fetching: goal.item().is_some(),
        ..Default::default()
    };
    if reckless || p.chased {
        return p;
    }
    // The timed way: to the goal, or, at it, whether staying is safe (else away and back later).
    memory.step = None;
    let now = memory.clock_s;
    // A plan is kept while it stays unseen by what the bot sees now (made again now and then, to
    // find a quicker way as guards move on); one that was seen anyway (the least seen there was) is
    // made again every time.
    let stale = memory.timed.as_ref().is_none_or(|t| {
        t.goal.distance(target) > 0.3
            || now - t.made_at >= REPLAN_S
            || (now - t.made_at >= QUICK_REPLAN_S
                && (t.way.seen_s > 0.0 || t.seen_ahead(forecast, &map.walls, now, me)))
    });
    if stale {
        let reach = rules::REACH * 0.8 - 0.2;
        memory.timed =
            spacetime::plan(&map.grid, forecast, &map.walls, me, target, reach).map(|w| Timed::new(w, now, target));
    }
    match memory.timed.as_mut().map(|t| t.order(now, me)) {
        Some(Order::Go(to, gait)) => {
            let gait = spacetime::safe_gait(forecast, &map.walls, me, gait);
            (p.way, memory.step) = (Some(gait), Some((to, gait)));
        }
        Some(Order::Hold) => p.hold = true,
        None => {}
    }
    let close = view.tuning.notice_radius + TOO_CLOSE_M;
    let crowded = view.guards.iter().any(|g| g.position.distance(me) < close);
    p.exposed = crowded || forecast.seen(me, 0.0, true, &map.walls);
    if p.exposed {
        return p;
    }
    if at_goal && matches!(p.action, Some(ViveMsg::Break(_))) {
        let hearing = view.tuning.hearing_at(view.alarm);
        let speed = view.tuning.hasted(view.tuning.investigate_speed, view.alarm);
        p.break_heard = view.guards.iter().any(|g| {
            map.nav.heard_margin(target, g.position, rules::GLASS_LOUDNESS * hearing) >= 0.0
                && map.nav.route_length(g.position, target) / speed < BREAK_HEADSTART_S
        });
        if p.break_heard {
            memory.quiet_since = None;
        }
        let since = *memory.quiet_since.get_or_insert(memory.clock_s);
        p.quiet_s = memory.clock_s - since;
    } else {
        memory.quiet_since = None;
    }
    p.hidden_here = forecast.hidden_for(me, HARBOUR_HOLD_S, &map.walls);
    let lure_due = memory.lured_at.is_none_or(|t| memory.clock_s - t > LURE_AFTER_S);
    if lure_due {
        let nearest = view.guards.iter().min_by(|a, b| a.position.distance(me).total_cmp(&b.position.distance(me)));
        let prop = view
            .me
            .carrying
            .iter()
            .copied()
            .find(|&i| view.items.iter().any(|it| it.id == i && matches!(it.kind, ItemKind::Prop)));
        if let (Some(g), Some(prop)) = (nearest, prop) {
            let hearing = view.tuning.hearing_at(view.alarm);
            p.lure = lure_aim(map, me, g.position, hearing).map(|aim| (prop, aim));
        }
    }
    p
}

/// Where to throw a prop so that a guard at `guard` walks away from Vive at `me`: of a few aims past
/// him, the one that lands farthest from Vive, of those that land beyond him (seen from Vive) and
/// within his hearing. `None` when every throw would hit a wall short of him (a thud by Vive's feet
/// would draw him to her).
fn lure_aim(map: &Map, me: Vec2, guard: Vec2, hearing: f32) -> Option<Vec2> {
    let ahead = guard - me;
    if ahead.length() < 0.1 {
        return None;
    }
    [0.0f32, 0.3, -0.3, 0.6, -0.6]
        .into_iter()
        .map(|turn| me + Vec2::from_angle(turn).rotate(ahead.normalize()) * rules::THROW_RANGE)
        .map(|aim| (aim, map.walls.throw_landing(&map.level, me, aim)))
        .filter(|(_, landing)| {
            landing.distance(me) > ahead.length() + LURE_BEYOND_M
                && map.nav.heard_margin(*landing, guard, rules::THUD_LOUDNESS * hearing) >= 0.0
        })
        .max_by(|a, b| a.1.distance(me).total_cmp(&b.1.distance(me)))
        .map(|(aim, _)| aim)
}

/// Keeps a route to `target` in memory, away from rooms with guards in them (straight for a reckless
/// bot); replanned when the target moves.
fn plan_route(map: &Map, memory: &mut Memory, view: &View<'_>, target: Vec2, reckless: bool) {
    let me = view.me.position;
    if memory.route_goal.is_none_or(|g| g.distance(target) > 0.3) || memory.route.is_empty() {
        let guard_rooms: Vec<usize> = view.guards.iter().filter_map(|g| map.nav.room_at(g.position)).collect();
        let cost = |room: usize| 1.0 + 3.0 * guard_rooms.iter().filter(|&&r| r == room).count() as f32;
        let route = if reckless { map.nav.route(me, target) } else { map.nav.route_avoiding(me, target, cost) };
        memory.route = route.unwrap_or_else(|| vec![target]);
        memory.route.reverse();
        memory.route_goal = Some(target);
    }
    while memory.route.len() > 1 && memory.route.last().is_some_and(|w| w.distance(me) < 0.25) {
        memory.route.pop();
    }
}

/// Carries `plan` out: (direction, gait, action). Updates the memory's timers.
pub(crate) fn carry_out(
    plan: Plan,
    map: &Map,
    memory: &mut Memory,
    view: &View<'_>,
    forecast: &Forecast,
) -> (Vec2, Gait, Option<ViveMsg>) {
    let me = view.me.position;
    if !matches!(plan, Plan::Flee) {
        memory.refuge = None;
    }
    memory.walked(me);
    match plan {
        Plan::Go(gait) => {
            let waypoint = memory.step.map(|(to, _)| to).or(memory.route.last().copied()).unwrap_or(me);
            ((waypoint - me).normalize_or_zero(), gait, None)
        }
        Plan::Act(action) => {
            if let ViveMsg::Break(c) = action
                && let Some(case) = view.cases.iter().find(|cv| cv.id == c)
            {
                memory.noises.push(Noise {
                    at: case.position,
                    when_s: memory.clock_s,
                    loudness: rules::GLASS_LOUDNESS,
                    evidence: true,
                });
            }
            (Vec2::ZERO, Gait::Walk, Some(action))
        }
        Plan::Wait => (Vec2::ZERO, Gait::Crouch, None),
        Plan::Throw(item, target) => {
            memory.lured_at = Some(memory.clock_s);
            let landing = map.walls.throw_landing(&map.level, me, target);
            memory.noises.push(Noise {
                at: landing,
                when_s: memory.clock_s,
                loudness: rules::THUD_LOUDNESS,
                evidence: false,
            });
            (Vec2::ZERO, Gait::Crouch, Some(ViveMsg::Throw { item, target }))
        }
        Plan::GiveUp => {
            if let Some(item) = memory.committed.take() {
                memory.avoid.push((item, memory.clock_s + AVOID_FOR_S));
            }
            memory.progress = None;
            memory.break_waited_s = 0.0;
            (Vec2::ZERO, Gait::Crouch, None)
        }
        Plan::Hide => {
            // The timed way is the least seen there is; without one, the nearest hiding place.
            let (direction, gait) = match (memory.step, &memory.timed) {
                (Some((to, gait)), _) => ((to - me).normalize_or_zero(), gait),
                (None, Some(_)) => (Vec2::ZERO, Gait::Crouch),
                (None, None) => hide(map, memory, view, forecast),
            };
            (direction, gait, None)
        }
        Plan::Flee => {
            // Run while a guard is after us; after losing him, walk on quietly (running is heard).
            let pursued = view.guards.iter().any(|g| g.alert == GuardAlert::Chasing);
            (flee(map, memory, view), if pursued { Gait::Run } else { Gait::Walk }, None)
        }
    }
}

/// Towards the nearest spot we can reach unseen that then stays hidden (places we have been, room
/// centres, spots around), crouching when a guard is near enough to see a standing Vive soon;
/// failing that, away along the flight route.
fn hide(map: &Map, memory: &mut Memory, view: &View<'_>, forecast: &Forecast) -> (Vec2, Gait) {
    let me = view.me.position;
    memory.route_goal = None;
    let standing_seen_at = view.tuning.sight_range_at(view.alarm, false, false) + 2.0;
    let near = view.guards.iter().any(|g| g.position.distance(me) < standing_seen_at);
    let (gait, speed) = if near { (Gait::Crouch, rules::CROUCH_SPEED) } else { (Gait::Walk, rules::WALK_SPEED) };
    let mut candidates: Vec<Vec2> = memory.trail.iter().rev().step_by(15).take(20).copied().collect();
    candidates.extend(map.nav.room_centres());
    for dx in [-3.0f32, 0.0, 3.0] {
        for dy in [-3.0f32, 0.0, 3.0] {
            candidates.push(me + Vec2::new(dx, dy));
        }
    }
    let best = candidates
        .into_iter()
        .filter(|c| map.nav.room_at(*c).is_some())
        .filter_map(|c| {
            let route = map.nav.route(me, c)?;
            let length = map.nav.route_length(me, c);
            forecast.hiding_place(me, &route, speed, near, &map.walls).then_some((length, route))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((_, route)) = best
        && let Some(first) = route.into_iter().find(|p| p.distance(me) > 0.2)
    {
        return ((first - me).normalize_or_zero(), gait);
    }
    // Nowhere better within reach: keep still and low if no guard sees this spot now, else get away.
    if !forecast.seen(me, 0.0, true, &map.walls) {
        return (Vec2::ZERO, Gait::Crouch);
    }
    (flee(map, memory, view), gait)
}

/// Towards the refuge chosen by [`pick_refuge`] (the workbench when there is none); the choice is
/// reconsidered every second and dropped once reached.
fn flee(map: &Map, memory: &mut Memory, view: &View<'_>) -> Vec2 {
    let me = view.me.position;
    if memory.refuge.is_some_and(|(r, _)| r.distance(me) < 1.5) {
        memory.refuge = None; // reached it and still in danger: pick the next one
    }
    // Think again every second (guards move), but switch only for a clearly better refuge.
    let now = memory.clock_s;
    if memory.refuge.is_none_or(|(_, at)| now - at > 1.0) {
        let current = memory.refuge.map(|(r, _)| r);
        memory.refuge = pick_refuge(map, view, current).map(|r| (r, now));
    }
    let refuge = memory.refuge.map_or(map.workbench, |(r, _)| r);
    let first = map.nav.route(me, refuge).and_then(|r| r.into_iter().find(|p| p.distance(me) > 0.3)).unwrap_or(refuge);
    memory.route_goal = None;
    (first - me).normalize_or_zero()
}

/// The spot we keep the most room at along the whole way there: ahead of every alerted guard, and
/// outside every patrolling guard's sight.
fn pick_refuge(map: &Map, view: &View<'_>, current: Option<Vec2>) -> Option<Vec2> {
    let me = view.me.position;
    let room_left = |p: Vec2| {
        let Some(route) = map.nav.route(me, p) else { return f32::NEG_INFINITY };
        let (mut last, mut mine, mut worst) = (me, 0.0f32, 20.0f32);
        for wp in points_along(me, &route) {
            mine += last.distance(wp);
            last = wp;
            for g in &view.guards {
                let theirs = map.nav.route_length(g.position, wp);
                worst = worst.min(match g.alert {
                    GuardAlert::Patrolling | GuardAlert::Returning => theirs - 6.0,
                    _ => theirs - mine,
                });
            }
        }
        worst + 0.05 * mine
    };
    let best = map
        .refuge_spots()
        .filter(|p| p.distance(me) > 6.0)
        .map(|p| (room_left(p), p))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    match (current, best) {
        (Some(c), Some((s, _))) if room_left(c) + 3.0 >= s => Some(c),
        (_, best) => best.map(|b| b.1),
    }
}

/// Points every metre along a polyline starting at `from`.
fn points_along(from: Vec2, route: &[Vec2]) -> Vec<Vec2> {
    let mut at = from;
    let mut points = Vec::new();
    for &wp in route {
        let steps = at.distance(wp).ceil().max(1.0) as usize;
        points.extend((1..=steps).map(|k| at.lerp(wp, k as f32 / steps as f32)));
        at = wp;
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::level::Level;

    #[test]
    fn a_lure_lands_beyond_the_guard_never_at_vives_feet() {
        let map = Map::new(&Level::museum());
        // In the workshop by the wall to the sculpture hall, the guard beyond that wall: every throw
        // towards him hits the wall at Vive's side and would bring him to her.
        let (me, guard) = (Vec2::new(8.5, 11.5), Vec2::new(19.0, 12.3));
        assert_eq!(lure_aim(&map, me, guard, 1.0), None);
        // In the open gallery: the prop lands past him, where he hears it.
        let (me, guard) = (Vec2::new(13.0, 3.0), Vec2::new(17.0, 4.0));
        let aim = lure_aim(&map, me, guard, 1.0).expect("a throw past him");
        let landing = map.walls.throw_landing(&map.level, me, aim);
        assert!(landing.distance(me) > guard.distance(me) + LURE_BEYOND_M, "lands at {landing}");
        assert!(map.nav.heard_margin(landing, guard, rules::THUD_LOUDNESS) >= 0.0);
    }
}
