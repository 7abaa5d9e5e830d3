//! Guard behaviour as small named decisions, tried in order; the first that applies wins.
//!
//! Perception (sight and hearing) is computed first from the world; each `<action>_if_<condition>`
//! function then looks only at the guard and its perception, so each can be tested without a network.

use glam::Vec2;
use heist_shared::level::{NavGraph, WallSet};
use heist_shared::protocol::{GuardAlert, GuardId, Stance};
use heist_shared::rules;

use super::Vive;

/// Patrol walking speed, m/s.
const PATROL_SPEED: f32 = 1.1;
/// Speed while investigating, m/s.
const INVESTIGATE_SPEED: f32 = 1.4;
/// Speed while chasing, m/s (below Vive's run, so a running Vive can get away).
const CHASE_SPEED: f32 = 2.6;
/// Sight range, metres.
const SIGHT_RANGE: f32 = 5.5;
/// Half of the vision cone, radians.
const SIGHT_HALF_ANGLE: f32 = 0.7;
/// Anyone this close is noticed whatever the facing, metres.
const NOTICE_RADIUS: f32 = 1.2;
/// How long a guard looks around at a spot before moving on, seconds.
const LOOK_AROUND_S: f32 = 3.0;
/// Turning speed, rad/s.
const TURN_RATE: f32 = 4.0;
/// How long a guard keeps staring at a vanished glimpse before checking the spot, seconds.
const STARE_S: f32 = 1.5;
/// Longest a guard stares at all before walking over to check, seconds.
const MAX_STARE_S: f32 = 4.0;

/// What a guard is doing and why.
#[derive(Clone, Debug, PartialEq)]
pub enum GuardState {
    /// Walking the route towards waypoint `next`.
    Patrol,
    /// Stopped, facing a glimpse of Vive at `at`.
    Suspicious {
        /// Where Vive was glimpsed.
        at: Vec2,
        /// Seconds since the glimpse was lost.
        unseen: f32,
        /// Seconds spent staring so far.
        stared: f32,
    },
    /// Walking to `at` (a noise or glimpse), then looking around.
    Investigate {
        /// The spot to check.
        at: Vec2,
        /// Seconds spent looking around once there.
        looked: f32,
    },
    /// Running after Vive, last seen at `last_seen`.
    Chase {
        /// Last known position.
        last_seen: Vec2,
    },
    /// Walking back to the route.
    Return,
}

/// A guard.
#[derive(Clone, Debug)]
pub struct Guard {
    /// Id.
    pub id: GuardId,
    /// Name.
    pub name: String,
    /// Position, metres.
    pub position: Vec2,
    /// Facing yaw, radians.
    pub facing: f32,
    /// Patrol route (closed loop).
    pub route: Vec<Vec2>,
    /// Next waypoint index.
    pub next: usize,
    /// Behaviour state.
    pub state: GuardState,
    /// The state as replicated.
    pub alert: GuardAlert,
    /// 0..1: how sure the guard is that someone is there (1 starts a chase).
    pub suspicion: f32,
    path: Vec<Vec2>,
    path_goal: Option<Vec2>,
}

/// What a guard senses this tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Perception {
    /// Vive is in sight.
    pub sees_vive: bool,
    /// Vive's position.
    pub vive_at: Vec2,
    /// Distance to Vive, metres.
    pub vive_distance: f32,
    /// The loudest noise heard this tick.
    pub heard: Option<Vec2>,
}

/// What a guard decided to do this tick.
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Catch Vive: the heist is lost.
    Catch,
    /// Run towards Vive.
    Chase(Vec2),
    /// Walk to a spot and look around.
    Investigate(Vec2),
    /// Stop and stare.
    Stare(Vec2),
    /// Look around where we stand.
    LookAround,
    /// Walk back to the route.
    Return,
    /// Walk the route.
    Patrol,
}

fn angle_of(v: Vec2) -> f32 {
    v.y.atan2(v.x)
}

fn wrap(a: f32) -> f32 {
    let mut a = a % std::f32::consts::TAU;
    if a > std::f32::consts::PI {
        a -= std::f32::consts::TAU;
    } else if a < -std::f32::consts::PI {
        a += std::f32::consts::TAU;
    }
    a
}

impl Guard {
    /// A guard standing at the start of its route.
    pub fn new(id: GuardId, name: String, route: Vec<Vec2>) -> Self {
        let position = route[0];
        let facing = route.get(1).map_or(0.0, |n| angle_of(*n - position));
        Self {
            id,
            name,
            position,
            facing,
            next: 1 % route.len(),
            route,
            state: GuardState::Patrol,
            alert: GuardAlert::Patrolling,
            suspicion: 0.0,
            path: Vec::new(),
            path_goal: None,
        }
    }

    /// How far this guard sees, metres, given its state and the alarm level.
    pub fn sight_range(&self, alarm: f32) -> f32 {
        let chase = if matches!(self.state, GuardState::Chase { .. }) { 1.5 } else { 1.0 };
        SIGHT_RANGE * chase * (1.0 + 0.1 * alarm)
    }

    /// True when `p` lies inside the vision cone (ignoring walls), for a target crouching or not.
    pub fn in_cone(&self, p: Vec2, crouching: bool, alarm: f32) -> bool {
        let d = p - self.position;
        let dist = d.length();
        if dist < NOTICE_RADIUS {
            return true;
        }
        let range = self.sight_range(alarm) * if crouching { 0.6 } else { 1.0 };
        let half = if matches!(self.state, GuardState::Chase { .. }) { 1.4 } else { SIGHT_HALF_ANGLE };
        dist <= range && wrap(angle_of(d) - self.facing).abs() <= half
    }
}

/// Sight and hearing for one guard.
pub fn perceive(
    guard: &Guard,
    vive: &Vive,
    walls: &WallSet,
    nav: &NavGraph,
    noises: &[(Vec2, f32)],
    alarm: f32,
) -> Perception {
    let crouching = vive.stance == Stance::Crouching;
    let sees_vive =
        guard.in_cone(vive.position, crouching, alarm) && walls.line_of_sight(guard.position, vive.position);
    let hearing = 1.0 + 0.25 * alarm;
    let heard = noises
        .iter()
        .map(|&(p, loud)| (p, nav.heard_margin(p, guard.position, loud * hearing)))
        .filter(|(_, margin)| *margin > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(p, _)| p);
    Perception { sees_vive, vive_at: vive.position, vive_distance: guard.position.distance(vive.position), heard }
}

/// Catch Vive when within arm's reach and aware of him.
fn catch_if_within_reach(_g: &Guard, p: &Perception) -> Option<Decision> {
    (p.sees_vive && p.vive_distance <= rules::CATCH_DISTANCE).then_some(Decision::Catch)
}

/// Chase when sure someone is there and still seeing him.
fn chase_if_sure(g: &Guard, p: &Perception) -> Option<Decision> {
    (p.sees_vive && (g.suspicion >= 1.0 || matches!(g.state, GuardState::Chase { .. })))
        .then_some(Decision::Chase(p.vive_at))
}

/// Keep running to the last known position after losing sight.
fn pursue_if_lost_sight(g: &Guard, _p: &Perception) -> Option<Decision> {
    match g.state {
        GuardState::Chase { last_seen } => Some(Decision::Investigate(last_seen)),
        _ => None,
    }
}

/// Stop and stare at a glimpse that is not yet certain; after a while, walk over to check.
fn stare_if_glimpsed(g: &Guard, p: &Perception) -> Option<Decision> {
    if !p.sees_vive {
        return None;
    }
    match g.state {
        GuardState::Suspicious { stared, .. } if stared >= MAX_STARE_S => Some(Decision::Investigate(p.vive_at)),
        // Already walking over to check: keep walking, towards the fresh glimpse.
        GuardState::Investigate { .. } => Some(Decision::Investigate(p.vive_at)),
        _ => Some(Decision::Stare(p.vive_at)),
    }
}

/// Walk to a noise.
fn investigate_if_heard(_g: &Guard, p: &Perception) -> Option<Decision> {
    p.heard.map(Decision::Investigate)
}

/// Keep staring a moment at a glimpse that vanished, then go and check the spot.
fn investigate_if_glimpse_lost(g: &Guard, _p: &Perception) -> Option<Decision> {
    match g.state {
        GuardState::Suspicious { at, unseen, stared } if unseen < STARE_S && stared < MAX_STARE_S => {
            Some(Decision::Stare(at))
        }
        GuardState::Suspicious { at, .. } => Some(Decision::Investigate(at)),
        _ => None,
    }
}

/// Carry on with an investigation under way; look around on arrival, then give up.
fn continue_investigation_if_started(g: &Guard, _p: &Perception) -> Option<Decision> {
    match g.state {
        GuardState::Investigate { at, looked } if looked < LOOK_AROUND_S => {
            if g.position.distance(at) < 0.8 {
                Some(Decision::LookAround)
            } else {
                Some(Decision::Investigate(at))
            }
        }
        GuardState::Investigate { .. } => Some(Decision::Return),
        _ => None,
    }
}

/// Walk back to the route until close to it.
fn return_if_off_route(g: &Guard, _p: &Perception) -> Option<Decision> {
    (g.state == GuardState::Return && g.position.distance(g.route[g.next]) > 0.8).then_some(Decision::Return)
}

/// Otherwise, patrol.
fn patrol_otherwise(_g: &Guard, _p: &Perception) -> Option<Decision> {
    Some(Decision::Patrol)
}

/// The decisions in priority order.
const DECISIONS: &[fn(&Guard, &Perception) -> Option<Decision>] = &[
    catch_if_within_reach,
    chase_if_sure,
    stare_if_glimpsed,
    investigate_if_heard,
    pursue_if_lost_sight,
    investigate_if_glimpse_lost,
    continue_investigation_if_started,
    return_if_off_route,
    patrol_otherwise,
];

/// The first decision that applies.
pub fn decide(g: &Guard, p: &Perception) -> Decision {
    DECISIONS.iter().find_map(|f| f(g, p)).unwrap_or(Decision::Patrol)
}

/// Updates suspicion, decides, and moves the guard; returns true when Vive is caught.
pub fn think_and_act(g: &mut Guard, p: &Perception, walls: &WallSet, nav: &NavGraph, alarm: f32, dt: f32) -> bool {
    if p.sees_vive {
        let range = g.sight_range(alarm).max(1.0);
        let closeness = (1.0 - p.vive_distance / range).clamp(0.0, 1.0);
        g.suspicion = (g.suspicion + dt * (0.3 + 1.2 * closeness)).min(1.0);
    } else if matches!(g.state, GuardState::Chase { .. }) {
        // Losing sight of the quarry: still alarmed, but a new glimpse must build up again.
        g.suspicion = g.suspicion.min(0.6);
    } else {
        g.suspicion = (g.suspicion - dt * 0.35).max(0.0);
    }
    let haste = 1.0 + 0.15 * alarm;
    match decide(g, p) {
        Decision::Catch => return true,
        Decision::Chase(at) => {
            g.state = GuardState::Chase { last_seen: at };
            g.alert = GuardAlert::Chasing;
            walk_towards(g, at, CHASE_SPEED * haste, walls, nav, dt);
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
        Decision::Investigate(at) => {
            let looked = match g.state {
                GuardState::Investigate { at: old, looked } if old == at => looked,
                _ => 0.0,
            };
            let chasing = matches!(g.state, GuardState::Chase { .. });
            g.state = GuardState::Investigate { at, looked };
            g.alert = GuardAlert::Investigating;
            let speed = if chasing { CHASE_SPEED } else { INVESTIGATE_SPEED };
            walk_towards(g, at, speed * haste, walls, nav, dt);
        }
        Decision::LookAround => {
            if let GuardState::Investigate { looked, .. } = &mut g.state {
                *looked += dt;
            }
            g.facing = wrap(g.facing + 1.2 * dt);
        }
        Decision::Return => {
            g.state = GuardState::Return;
            g.alert = GuardAlert::Returning;
            let goal = nearest_waypoint(g);
            g.next = goal;
            walk_towards(g, g.route[goal], INVESTIGATE_SPEED * haste, walls, nav, dt);
        }
        Decision::Patrol => {
            g.state = GuardState::Patrol;
            g.alert = GuardAlert::Patrolling;
            if g.position.distance(g.route[g.next]) < 0.3 {
                g.next = (g.next + 1) % g.route.len();
            }
            let target = g.route[g.next];
            walk_towards(g, target, PATROL_SPEED * haste, walls, nav, dt);
        }
    }
    false
}

fn nearest_waypoint(g: &Guard) -> usize {
    (0..g.route.len())
        .min_by(|&a, &b| g.position.distance(g.route[a]).total_cmp(&g.position.distance(g.route[b])))
        .unwrap_or(0)
}

fn turn_towards(g: &mut Guard, yaw: f32, dt: f32) {
    let diff = wrap(yaw - g.facing);
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

#[cfg(test)]
mod tests {
    use super::*;

    fn guard() -> Guard {
        Guard::new(GuardId(0), "Test".into(), vec![Vec2::ZERO, Vec2::new(10.0, 0.0)])
    }

    fn seen(at: Vec2, distance: f32) -> Perception {
        Perception { sees_vive: true, vive_at: at, vive_distance: distance, heard: None }
    }

    #[test]
    fn a_guard_who_sees_vive_at_arms_length_catches_him() {
        assert_eq!(decide(&guard(), &seen(Vec2::X * 0.5, 0.5)), Decision::Catch);
    }

    #[test]
    fn a_first_glimpse_makes_a_guard_stare_not_chase() {
        assert_eq!(decide(&guard(), &seen(Vec2::X * 6.0, 6.0)), Decision::Stare(Vec2::X * 6.0));
    }

    #[test]
    fn a_guard_stops_staring_after_a_while_and_walks_over() {
        let mut g = guard();
        g.state = GuardState::Suspicious { at: Vec2::X * 5.0, unseen: 0.0, stared: MAX_STARE_S + 0.1 };
        assert_eq!(decide(&g, &seen(Vec2::X * 5.0, 5.0)), Decision::Investigate(Vec2::X * 5.0));
        assert_eq!(decide(&g, &Perception::default()), Decision::Investigate(Vec2::X * 5.0));
    }

    #[test]
    fn a_guard_checking_a_spot_keeps_walking_when_it_glimpses_vive_again() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::X * 3.0, looked: 0.0 };
        assert_eq!(decide(&g, &seen(Vec2::X * 6.0, 6.0)), Decision::Investigate(Vec2::X * 6.0));
    }

    #[test]
    fn a_sure_guard_chases() {
        let mut g = guard();
        g.suspicion = 1.0;
        assert_eq!(decide(&g, &seen(Vec2::X * 6.0, 6.0)), Decision::Chase(Vec2::X * 6.0));
    }

    #[test]
    fn a_noise_sends_a_patrolling_guard_to_investigate() {
        let p = Perception { heard: Some(Vec2::new(3.0, 4.0)), ..Default::default() };
        assert_eq!(decide(&guard(), &p), Decision::Investigate(Vec2::new(3.0, 4.0)));
    }

    #[test]
    fn a_guard_who_lost_sight_runs_to_the_last_known_position() {
        let mut g = guard();
        g.state = GuardState::Chase { last_seen: Vec2::new(5.0, 1.0) };
        assert_eq!(decide(&g, &Perception::default()), Decision::Investigate(Vec2::new(5.0, 1.0)));
    }

    #[test]
    fn after_looking_around_a_guard_returns_to_the_route() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::ZERO, looked: LOOK_AROUND_S + 0.1 };
        assert_eq!(decide(&g, &Perception::default()), Decision::Return);
    }

    #[test]
    fn the_cone_excludes_what_is_behind_unless_very_close() {
        let g = guard(); // faces +x
        assert!(g.in_cone(Vec2::new(5.0, 0.0), false, 0.0));
        assert!(!g.in_cone(Vec2::new(-5.0, 0.0), false, 0.0));
        assert!(g.in_cone(Vec2::new(-1.0, 0.0), false, 0.0));
        assert!(!g.in_cone(Vec2::new(7.0, 0.0), true, 0.0), "crouching shortens sight");
    }
}
