//! Carrying a guard's decision out: suspicion builds and fades, the state changes, the guard turns and
//! walks (along the room graph), and what the game must do besides (Vive caught, a radio call, a case
//! reported) is handed back.

use glam::Vec2;
use heist_shared::level::{NavGraph, WallSet, patrol};
use heist_shared::protocol::{GuardAlert, RadioAbout};
use heist_shared::rules::GUARD_TURN_RATE as TURN_RATE;
use heist_shared::rules::{self, GuardTuning};

use super::{Decision, Guard, GuardState, Perception, SEARCH_LOOK_S, angle_of, decide, wrap};

/// A guard radios about Vive at most this often, seconds (a report of evidence always goes out).
pub const RADIO_COOLDOWN_S: f32 = 10.0;

/// What the game must do after a guard acted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Acted {
    /// The guard caught Vive: the heist is lost.
    pub caught: bool,
    /// The guard radios the others: what about, and where.
    pub radio: Option<(RadioAbout, Vec2)>,
    /// The guard reported this broken case (the alarm goes up).
    pub reported: Option<usize>,
}

/// Updates suspicion, decides, and moves the guard.
pub fn think_and_act(
    g: &mut Guard,
    p: &Perception,
    walls: &WallSet,
    nav: &NavGraph,
    alarm: u8,
    t: &GuardTuning,
    dt: f32,
) -> Acted {
    let mut acted = Acted::default();
    g.since_radio_s += dt;
    if p.sees_vive {
        let range = g.sight_range(alarm, t).max(1.0);
        let closeness = (1.0 - p.vive_distance / range).clamp(0.0, 1.0);
        g.suspicion = (g.suspicion + dt * t.suspicion_rate * (0.3 + 1.2 * closeness)).min(1.0);
    } else if matches!(g.state, GuardState::Chase { .. }) {
        // Losing sight of the quarry: still alarmed, but a new glimpse must build up again.
        g.suspicion = g.suspicion.min(0.6);
    } else {
        g.suspicion = (g.suspicion - dt * 0.35).max(0.0);
    }
    let haste = t.hasted(1.0, alarm);
    match decide(g, p) {
        Decision::Catch => acted.caught = true,
        Decision::Chase(at) => {
            g.state = GuardState::Chase { last_seen: at };
            g.alert = GuardAlert::Chasing;
            g.orders = None;
            if g.since_radio_s >= RADIO_COOLDOWN_S {
                g.since_radio_s = 0.0;
                acted.radio = Some((RadioAbout::Sighting, at));
            }
            walk_towards(g, at, t.chase_speed * haste, walls, nav, dt);
        }
        Decision::Stare(at) => {
            let (unseen, stared) = match g.state {
                GuardState::Suspicious { unseen, stared, .. } => {
                    (if p.sees_vive { 0.0 } else { unseen + dt }, stared + dt)
                }
                _ => (0.0, 0.0),
            };
            g.state = GuardState::Suspicious { at, unseen, stared };
            g.alert = GuardAlert::Suspicious;
            turn_towards(g, angle_of(at - g.position), dt);
        }
        Decision::Investigate(at, then_search) => investigate(g, at, then_search, t, haste, walls, nav, dt),
        Decision::Report(case, at) => {
            acted.reported = Some(case);
            g.since_radio_s = 0.0;
            acted.radio = Some((RadioAbout::Evidence, at));
            investigate(g, at, false, t, haste, walls, nav, dt);
        }
        Decision::LookAround => {
            match &mut g.state {
                GuardState::Investigate { looked, .. } | GuardState::Search { looked, .. } => *looked += dt,
                _ => {}
            }
            g.facing = wrap(g.facing + 1.2 * dt);
        }
        Decision::Search(spots) => {
            let spots = if spots.is_empty() {
                // Around where this guard looked last (or stands).
                let at = match g.state {
                    GuardState::Investigate { at, .. } => at,
                    _ => g.position,
                };
                patrol::search_spots(nav, at, super::SEARCH_SPOTS)
            } else {
                g.orders = None;
                spots
            };
            search(g, spots, t, haste, walls, nav, dt);
        }
        Decision::Return => {
            g.state = GuardState::Return;
            g.alert = GuardAlert::Returning;
            let goal = super::nearest_waypoint(g);
            g.next = goal;
            walk_towards(g, g.route[goal], t.investigate_speed * haste, walls, nav, dt);
        }
        Decision::Patrol => {
            g.state = GuardState::Patrol;
            g.alert = GuardAlert::Patrolling;
            if g.position.distance(g.route[g.next]) < 0.3 {
                g.next = (g.next + 1) % g.route.len();
            }
            let target = g.route[g.next];
            walk_towards(g, target, t.patrol_speed * haste, walls, nav, dt);
        }
    }
    acted
}

#[allow(clippy::too_many_arguments)]
fn investigate(
    g: &mut Guard,
    at: Vec2,
    then_search: bool,
    t: &GuardTuning,
    haste: f32,
    walls: &WallSet,
    nav: &NavGraph,
    dt: f32,
) {
    let looked = match g.state {
        GuardState::Investigate { at: old, looked, .. } if old == at => looked,
        _ => 0.0,
    };
    let chasing = matches!(g.state, GuardState::Chase { .. });
    g.state = GuardState::Investigate { at, looked, then_search };
    g.alert = GuardAlert::Investigating;
    let speed = if chasing { t.chase_speed } else { t.investigate_speed };
    walk_towards(g, at, speed * haste, walls, nav, dt);
}

/// Walks to the next spot of `spots` (moving on from one looked around at long enough).
fn search(g: &mut Guard, spots: Vec<Vec2>, t: &GuardTuning, haste: f32, walls: &WallSet, nav: &NavGraph, dt: f32) {
    let (mut next, mut looked) = match &g.state {
        GuardState::Search { spots: old, next, looked } if *old == spots => (*next, *looked),
        _ => (0, 0.0),
    };
    if spots.get(next).is_some_and(|s| g.position.distance(*s) < rules::ARRIVED_M) && looked >= SEARCH_LOOK_S {
        next += 1;
        looked = 0.0;
    }
    let goal = spots.get(next).copied();
    g.state = GuardState::Search { spots, next, looked };
    g.alert = GuardAlert::Searching;
    if let Some(goal) = goal {
        walk_towards(g, goal, t.investigate_speed * haste, walls, nav, dt);
    }
}

/// Turns towards `yaw` at [`TURN_RATE`], the short way round; an about-turn (either way about as short)
/// always to the guard's left (anticlockwise seen from above), so a player can tell which way a guard
/// at the end of his round will sweep his look (`heist_shared::rules::about_turn`).
fn turn_towards(g: &mut Guard, yaw: f32, dt: f32) {
    let diff = heist_shared::rules::about_turn(wrap(yaw - g.facing));
    g.facing = wrap(g.facing + diff.clamp(-TURN_RATE * dt, TURN_RATE * dt));
}

fn walk_towards(g: &mut Guard, goal: Vec2, speed: f32, walls: &WallSet, nav: &NavGraph, dt: f32) {
    if g.path_goal.is_none_or(|pg| pg.distance(goal) > 0.5) {
        g.path = nav.route(g.position, goal).unwrap_or_else(|| vec![goal]);
        g.path.reverse();
        g.path_goal = Some(goal);
    }
    let mut step = speed * dt;
    while step > 0.0 {
        let Some(&wp) = g.path.last() else { break };
        let to = wp - g.position;
        let dist = to.length();
        if dist <= step {
            g.position = walls.slide(g.position, to, 0.25);
            step -= dist;
            g.path.pop();
        } else {
            g.position = walls.slide(g.position, to / dist * step, 0.25);
            turn_towards(g, angle_of(to), dt);
            break;
        }
    }
    if g.path.is_empty() {
        g.path_goal = None;
    }
}
