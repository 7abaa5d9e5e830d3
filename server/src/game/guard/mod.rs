//! Guard behaviour as small named decisions, tried in order; the first that applies wins.
//!
//! Perception (sight, hearing, evidence, radio orders) is computed first from the world
//! ([`perceive`]); each `<action>_if_<condition>` function then looks only at the guard and its
//! perception, so each can be tested without a network; [`act`] carries the decision out. Guards work
//! together: one who is sure he saw Vive, or who finds a broken case, radios the others
//! (`game::radio`), and those in range come to search the rooms around (`heist_shared::level::patrol`).

mod act;
mod perceive;

pub use act::think_and_act;
pub use perceive::{Body, perceive};

use glam::Vec2;
use heist_shared::protocol::{GuardAlert, GuardId};
use heist_shared::rules::{self, GuardTuning};

/// How long a guard keeps staring at a vanished glimpse before checking the spot, seconds.
const STARE_S: f32 = 1.5;
/// Longest a guard stares at all before walking over to check, seconds.
const MAX_STARE_S: f32 = 4.0;
pub use heist_shared::rules::{LOOK_AROUND_S, SEARCH_LOOK_S, SEARCH_SPOTS};

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
    /// Walking to `at` (a noise, a glimpse, where Vive was last seen), then looking around.
    Investigate {
        /// The spot to check.
        at: Vec2,
        /// Seconds spent looking around once there.
        looked: f32,
        /// After looking, search the rooms around (Vive was seen here) instead of going back.
        then_search: bool,
    },
    /// Running after Vive, last seen at `last_seen`.
    Chase {
        /// Last known position.
        last_seen: Vec2,
    },
    /// Visiting `spots` in turn, looking around at each.
    Search {
        /// The spots to visit.
        spots: Vec<Vec2>,
        /// The one being walked to or looked around at.
        next: usize,
        /// Seconds spent looking around there.
        looked: f32,
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
    /// Patrol route (closed loop): the level's, or the alarm's ([`heist_shared::level::patrol::alert_route`]).
    pub route: Vec<Vec2>,
    /// Next waypoint index.
    pub next: usize,
    /// Behaviour state.
    pub state: GuardState,
    /// The state as replicated.
    pub alert: GuardAlert,
    /// 0..1: how sure the guard is that someone is there (1 starts a chase).
    pub suspicion: f32,
    /// Spots to search that a radio call assigned this guard, not yet acted on.
    pub orders: Option<Vec<Vec2>>,
    /// Seconds since this guard last radioed (a guard radios once per [`rules`]-independent cooldown).
    pub since_radio_s: f32,
    path: Vec<Vec2>,
    path_goal: Option<Vec2>,
}

/// What a guard senses this tick.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Perception {
    /// Vive is in sight.
    pub sees_vive: bool,
    /// Vive's position.
    pub vive_at: Vec2,
    /// Distance to Vive, metres.
    pub vive_distance: f32,
    /// The loudest noise heard this tick.
    pub heard: Option<Vec2>,
    /// A broken case in sight that nobody has reported: (case index, where).
    pub evidence: Option<(usize, Vec2)>,
    /// Spots a radio call asks this guard to search.
    pub radioed: Option<Vec<Vec2>>,
}

/// What a guard decided to do this tick.
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// Catch Vive: the heist is lost.
    Catch,
    /// Run towards Vive.
    Chase(Vec2),
    /// Walk to a spot and look around (then search the rooms around, when the flag says so).
    Investigate(Vec2, bool),
    /// Stop and stare.
    Stare(Vec2),
    /// Look around where we stand.
    LookAround,
    /// Report a broken case (case index, where): the alarm goes up, the others are radioed (to search
    /// around it), and the guard goes to look at it.
    Report(usize, Vec2),
    /// Search these spots in turn.
    Search(Vec<Vec2>),
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
            orders: None,
            since_radio_s: f32::INFINITY,
            path: Vec::new(),
            path_goal: None,
        }
    }

    /// How far this guard sees, metres, given its state, the alarm level and the tuning.
    pub fn sight_range(&self, alarm: u8, t: &GuardTuning) -> f32 {
        t.sight_range_at(alarm, self.is_chasing(), false)
    }

    /// True while running after Vive.
    pub fn is_chasing(&self) -> bool {
        matches!(self.state, GuardState::Chase { .. })
    }

    /// True when `p` lies inside the vision cone (ignoring walls), for a target crouching or not.
    pub fn in_cone(&self, p: Vec2, crouching: bool, alarm: u8, t: &GuardTuning) -> bool {
        let d = p - self.position;
        let dist = d.length();
        if dist < t.notice_radius {
            return true;
        }
        let range = t.sight_range_at(alarm, self.is_chasing(), crouching);
        let half = t.half_angle(self.is_chasing());
        dist <= range && wrap(angle_of(d) - self.facing).abs() <= half
    }

    /// Switches to `route` (the alarm changed the patrols), heading for its nearest waypoint.
    pub fn set_route(&mut self, route: Vec<Vec2>) {
        if route.is_empty() || route == self.route {
            return;
        }
        self.route = route;
        self.next = nearest_waypoint(self);
    }

    /// True while the guard is busy with Vive himself (chasing, staring, checking a spot), when a radio
    /// call does not pull him away.
    pub fn is_engaged(&self) -> bool {
        matches!(self.state, GuardState::Chase { .. } | GuardState::Suspicious { .. } | GuardState::Investigate { .. })
    }
}

pub(crate) fn nearest_waypoint(g: &Guard) -> usize {
    (0..g.route.len())
        .min_by(|&a, &b| g.position.distance(g.route[a]).total_cmp(&g.position.distance(g.route[b])))
        .unwrap_or(0)
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

/// Stop and stare at a glimpse that is not yet certain; after a while, walk over to check.
fn stare_if_glimpsed(g: &Guard, p: &Perception) -> Option<Decision> {
    if !p.sees_vive {
        return None;
    }
    match g.state {
        GuardState::Suspicious { stared, .. } if stared >= MAX_STARE_S => Some(Decision::Investigate(p.vive_at, false)),
        // Already walking over to check: keep walking, towards the fresh glimpse.
        GuardState::Investigate { then_search, .. } => Some(Decision::Investigate(p.vive_at, then_search)),
        _ => Some(Decision::Stare(p.vive_at)),
    }
}

/// Walk to a noise.
fn investigate_if_heard(_g: &Guard, p: &Perception) -> Option<Decision> {
    p.heard.map(|at| Decision::Investigate(at, false))
}

/// Keep running to the last known position after losing sight, and search around it afterwards.
fn pursue_if_lost_sight(g: &Guard, _p: &Perception) -> Option<Decision> {
    match g.state {
        GuardState::Chase { last_seen } => Some(Decision::Investigate(last_seen, true)),
        _ => None,
    }
}

/// Keep staring a moment at a glimpse that vanished, then go and check the spot.
fn investigate_if_glimpse_lost(g: &Guard, _p: &Perception) -> Option<Decision> {
    match g.state {
        GuardState::Suspicious { at, unseen, stared } if unseen < STARE_S && stared < MAX_STARE_S => {
            Some(Decision::Stare(at))
        }
        GuardState::Suspicious { at, .. } => Some(Decision::Investigate(at, false)),
        _ => None,
    }
}

/// Report a broken case found on the round (nobody reported it yet).
fn report_if_evidence_found(_g: &Guard, p: &Perception) -> Option<Decision> {
    p.evidence.map(|(case, at)| Decision::Report(case, at))
}

/// Carry on with an investigation under way; look around on arrival; then search the rooms around
/// (where Vive was seen) or give up.
fn continue_investigation_if_started(g: &Guard, p: &Perception) -> Option<Decision> {
    let GuardState::Investigate { at, looked, then_search } = g.state else { return None };
    if looked < LOOK_AROUND_S {
        return Some(if g.position.distance(at) < rules::ARRIVED_M {
            Decision::LookAround
        } else {
            Decision::Investigate(at, then_search)
        });
    }
    // The area around is searched where Vive was seen; a radio call's own spots come first.
    match (&p.radioed, then_search) {
        (Some(spots), _) => Some(Decision::Search(spots.clone())),
        (None, true) => Some(Decision::Search(Vec::new())),
        (None, false) => Some(Decision::Return),
    }
}

/// Come and search where a radio call asks (unless busy with Vive, handled above).
fn converge_if_radioed(_g: &Guard, p: &Perception) -> Option<Decision> {
    p.radioed.clone().map(Decision::Search)
}

/// Go on searching: walk to the next spot, look around there, then the next; back to the round after
/// the last.
fn continue_search_if_started(g: &Guard, _p: &Perception) -> Option<Decision> {
    let GuardState::Search { spots, next, looked } = &g.state else { return None };
    let Some(spot) = spots.get(*next) else { return Some(Decision::Return) };
    if g.position.distance(*spot) < rules::ARRIVED_M && *looked < SEARCH_LOOK_S {
        return Some(Decision::LookAround);
    }
    Some(Decision::Search(spots.clone()))
}

/// Walk back to the route until close to it.
fn return_if_off_route(g: &Guard, _p: &Perception) -> Option<Decision> {
    (g.state == GuardState::Return && g.position.distance(g.route[g.next]) > rules::ARRIVED_M)
        .then_some(Decision::Return)
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
    report_if_evidence_found,
    continue_investigation_if_started,
    converge_if_radioed,
    continue_search_if_started,
    return_if_off_route,
    patrol_otherwise,
];

/// The first decision that applies.
pub fn decide(g: &Guard, p: &Perception) -> Decision {
    DECISIONS.iter().find_map(|f| f(g, p)).unwrap_or(Decision::Patrol)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn guard() -> Guard {
        Guard::new(GuardId(0), "Test".into(), vec![Vec2::ZERO, Vec2::new(10.0, 0.0)])
    }

    fn seen(at: Vec2, distance: f32) -> Perception {
        Perception { sees_vive: true, vive_at: at, vive_distance: distance, ..Default::default() }
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
        assert_eq!(decide(&g, &seen(Vec2::X * 5.0, 5.0)), Decision::Investigate(Vec2::X * 5.0, false));
        assert_eq!(decide(&g, &Perception::default()), Decision::Investigate(Vec2::X * 5.0, false));
    }

    #[test]
    fn a_guard_checking_a_spot_keeps_walking_when_it_glimpses_vive_again() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::X * 3.0, looked: 0.0, then_search: false };
        assert_eq!(decide(&g, &seen(Vec2::X * 6.0, 6.0)), Decision::Investigate(Vec2::X * 6.0, false));
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
        assert_eq!(decide(&guard(), &p), Decision::Investigate(Vec2::new(3.0, 4.0), false));
    }

    #[test]
    fn a_guard_who_lost_sight_runs_to_the_last_known_position_and_will_search_around_it() {
        let mut g = guard();
        g.state = GuardState::Chase { last_seen: Vec2::new(5.0, 1.0) };
        assert_eq!(decide(&g, &Perception::default()), Decision::Investigate(Vec2::new(5.0, 1.0), true));
    }

    #[test]
    fn after_looking_around_a_noise_a_guard_returns_to_the_route() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::ZERO, looked: LOOK_AROUND_S + 0.1, then_search: false };
        assert_eq!(decide(&g, &Perception::default()), Decision::Return);
    }

    #[test]
    fn after_looking_around_where_vive_was_seen_a_guard_searches_the_rooms_around() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::ZERO, looked: LOOK_AROUND_S + 0.1, then_search: true };
        assert_eq!(decide(&g, &Perception::default()), Decision::Search(Vec::new()));
    }

    #[test]
    fn a_radio_call_brings_a_patrolling_guard_to_search_its_share_of_the_spots() {
        let spots = vec![Vec2::new(3.0, 3.0), Vec2::new(8.0, 1.0)];
        let p = Perception { radioed: Some(spots.clone()), ..Default::default() };
        assert_eq!(decide(&guard(), &p), Decision::Search(spots));
    }

    #[test]
    fn a_radio_call_does_not_pull_a_guard_away_from_a_noise_it_is_checking() {
        let mut g = guard();
        g.state = GuardState::Investigate { at: Vec2::X * 4.0, looked: 0.0, then_search: false };
        let p = Perception { radioed: Some(vec![Vec2::new(30.0, 0.0)]), ..Default::default() };
        assert_eq!(decide(&g, &p), Decision::Investigate(Vec2::X * 4.0, false));
    }

    #[test]
    fn a_broken_case_found_on_the_round_is_reported() {
        let p = Perception { evidence: Some((2, Vec2::new(4.0, 1.0))), ..Default::default() };
        assert_eq!(decide(&guard(), &p), Decision::Report(2, Vec2::new(4.0, 1.0)));
    }

    #[test]
    fn a_searching_guard_looks_around_at_each_spot_then_walks_to_the_next_and_returns_after_the_last() {
        let mut g = guard();
        let spots = vec![Vec2::ZERO, Vec2::new(6.0, 0.0)];
        g.state = GuardState::Search { spots: spots.clone(), next: 0, looked: 0.0 };
        assert_eq!(decide(&g, &Perception::default()), Decision::LookAround);
        g.state = GuardState::Search { spots: spots.clone(), next: 1, looked: 0.0 };
        assert_eq!(decide(&g, &Perception::default()), Decision::Search(spots.clone()));
        g.state = GuardState::Search { spots, next: 2, looked: 0.0 };
        assert_eq!(decide(&g, &Perception::default()), Decision::Return);
    }

    #[test]
    fn at_the_end_of_his_round_a_guard_about_turns_to_his_left() {
        // Bruno walks +x to the east end of the galleries' round, then back: his look sweeps through
        // +z (his left), as the published rule says (`rules::about_turn`), never through −z.
        let level = heist_shared::level::Level::museum();
        let (walls, nav) = (heist_shared::level::WallSet::new(&level), heist_shared::level::NavGraph::new(&level));
        let mut g = Guard::new(GuardId(0), "Bruno".into(), level.guards[0].route.clone());
        g.position = g.route[1] - Vec2::new(0.5, 0.0);
        (g.facing, g.next) = (0.0, 1);
        let (t, dt) = (GuardTuning::default(), 1.0 / 60.0);
        let mut swept = Vec::new();
        for _ in 0..90 {
            act::think_and_act(&mut g, &Perception::default(), &walls, &nav, 0, &t, dt);
            swept.push(g.facing);
        }
        assert!(swept.iter().any(|f| (f - std::f32::consts::FRAC_PI_2).abs() < 0.1), "through +z: {swept:?}");
        assert!(swept.iter().all(|f| *f > -0.1), "never through −z: {swept:?}");
        assert!((wrap(g.facing - std::f32::consts::PI)).abs() < 1e-3, "turned about: {}", g.facing);
    }

    #[test]
    fn the_cone_excludes_what_is_behind_unless_very_close() {
        let g = guard(); // faces +x
        let t = GuardTuning::default();
        assert!(g.in_cone(Vec2::new(5.0, 0.0), false, 0, &t));
        assert!(!g.in_cone(Vec2::new(-5.0, 0.0), false, 0, &t));
        assert!(g.in_cone(Vec2::new(-1.0, 0.0), false, 0, &t));
        assert!(!g.in_cone(Vec2::new(7.0, 0.0), true, 0, &t), "crouching shortens sight");
    }
}
