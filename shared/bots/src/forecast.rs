//! Where guards will be and look in the next seconds, from their public patrol routes (the level's, or
//! the ones the alarm switches them to: `heist_shared::level::patrol::alert_route`).
//!
//! A patrolling guard walks its route at patrol speed; the bot replays that walk ahead of time. A guard
//! that is not patrolling (staring, investigating, chasing, searching, returning) is unpredictable: the
//! bot treats it as coming at it and looking every way.

use glam::Vec2;
use heist_shared::level::WallSet;
use heist_shared::protocol::{GuardAlert, GuardView};
use heist_shared::rules::GuardTuning;

/// The bot's caution on top of the guards' published sight range, metres.
const RANGE_MARGIN: f32 = 1.0;
/// The bot's caution on top of the guards' published half-angle of view, radians.
const ANGLE_MARGIN: f32 = 0.25;
/// The bot's caution on top of the guards' all-round noticing radius, metres.
const ALL_ROUND_MARGIN: f32 = 1.0;

/// One guard's future.
enum Future {
    /// Walks the route: (route, index of the waypoint it heads to, position now, speed).
    Patrol(Vec<Vec2>, usize, Vec2, f32),
    /// Unpredictable: assumed to walk straight at the bot, looking all round.
    Alert(Vec2, Vec2),
}

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

impl Forecast {
    /// Builds the forecast from what the client sees now; `me` is the bot's position, `tuning` what the
    /// guards can do on the session's difficulty, `routes` each guard's patrol (by guard id) now.
    pub fn new(tuning: &GuardTuning, routes: &[Vec<Vec2>], guards: &[&GuardView], alarm: u8, me: Vec2) -> Self {
        let futures = guards
            .iter()
            .map(|g| {
                let route = routes.get(usize::from(g.id.0)).cloned().unwrap_or_default();
                if g.alert != GuardAlert::Patrolling || route.len() < 2 {
                    return Future::Alert(g.position, me);
                }
                let facing = Vec2::from_angle(g.facing);
                let next = (0..route.len())
                    .filter(|&i| route[i].distance(g.position) > 0.3)
                    .max_by(|&a, &b| {
                        let da = (route[a] - g.position).normalize_or_zero().dot(facing);
                        let db = (route[b] - g.position).normalize_or_zero().dot(facing);
                        da.total_cmp(&db)
                    })
                    .unwrap_or(0);
                Future::Patrol(route, next, g.position, tuning.hasted(tuning.patrol_speed, alarm))
            })
            .collect();
        Self { futures, alarm, tuning: *tuning }
    }

    /// Where a guard last seen as `last`, `ago_s` seconds ago, is likely now (what a player who lost
    /// sight of it would guess): walked on along its route if it was patrolling; where it was if it was
    /// alerted, for `alert_memory_s`, and after that back on its patrol from there.
    pub fn imagine(
        tuning: &GuardTuning,
        routes: &[Vec<Vec2>],
        last: &GuardView,
        alarm: u8,
        ago_s: f32,
        alert_memory_s: f32,
    ) -> GuardView {
        if last.alert != GuardAlert::Patrolling && ago_s < alert_memory_s {
            return last.clone();
        }
        let calm = GuardView { alert: GuardAlert::Patrolling, ..last.clone() };
        let ago_s = if last.alert == GuardAlert::Patrolling { ago_s } else { ago_s - alert_memory_s };
        let forecast = Self::new(tuning, routes, &[&calm], alarm, last.position);
        match forecast.futures.first() {
            Some(Future::Patrol(..)) => {
                let (position, facing) = forecast.pose(0, ago_s);
                GuardView { position, facing: facing.unwrap_or(last.facing), ..calm }
            }
            _ => calm,
        }
    }

    /// Pose (position, facing) of guard `i` after `t` seconds.
    fn pose(&self, i: usize, t: f32) -> (Vec2, Option<f32>) {
        match &self.futures[i] {
            Future::Alert(p, towards) => {
                let d = *towards - *p;
                let walk = (self.tuning.investigate_speed * t).min((d.length() - 1.0).max(0.0));
                (*p + d.normalize_or_zero() * walk, None)
            }
            Future::Patrol(route, next, start, speed) => {
                let mut at = *start;
                let mut target = *next;
                let mut left = t * speed;
                loop {
                    let to = route[target] - at;
                    let d = to.length();
                    if d >= left || d < 1e-4 && left <= 0.0 {
                        let dir = to.normalize_or_zero();
                        return (at + dir * left.min(d), Some(angle_of(if dir == Vec2::ZERO { Vec2::X } else { dir })));
                    }
                    left -= d;
                    at = route[target];
                    target = (target + 1) % route.len();
                }
            }
        }
    }

    /// True when some guard could see a person at `p` (crouching or not) `t` seconds from now.
    pub fn seen(&self, p: Vec2, t: f32, crouching: bool, walls: &WallSet) -> bool {
        let t_ = &self.tuning;
        let margined = GuardTuning { sight_range: t_.sight_range + RANGE_MARGIN, ..*t_ };
        let range = margined.sight_range_at(self.alarm, false, crouching);
        let (all_round, half_angle) = (t_.notice_radius + ALL_ROUND_MARGIN, t_.half_angle(false) + ANGLE_MARGIN);
        (0..self.futures.len()).any(|i| {
            let (g, facing) = self.pose(i, t);
            let d = p - g;
            let dist = d.length();
            let in_view = match facing {
                _ if dist < all_round => true,
                None => dist < range,
                Some(f) => dist < range && wrap(angle_of(d) - f).abs() < half_angle,
            };
            in_view && walls.line_of_sight(g, p)
        })
    }

    /// True when `p` stays unseen (crouching) for the next `horizon` seconds.
    pub fn hidden_for(&self, p: Vec2, horizon: f32, walls: &WallSet) -> bool {
        (0..=(horizon * 4.0) as usize).all(|k| !self.seen(p, k as f32 * 0.25, true, walls))
    }

    /// True when walking the polyline from `from` through `path` at `speed` stays unseen for `horizon` s.
    pub fn path_hidden(
        &self,
        from: Vec2,
        path: &[Vec2],
        speed: f32,
        horizon: f32,
        crouching: bool,
        walls: &WallSet,
    ) -> bool {
        let mut at = from;
        let mut t = 0.0;
        let step = 0.25;
        for &wp in path {
            while at.distance(wp) > 1e-3 {
                if self.seen(at, t, crouching, walls) {
                    return false;
                }
                if t >= horizon {
                    return true;
                }
                let d = (wp - at).length().min(speed * step);
                at += (wp - at).normalize_or_zero() * d;
                t += step;
            }
        }
        // Arrived: the goal itself must stay hidden for what is left of the horizon.
        (0..=((horizon - t).max(0.0) * 4.0) as usize).all(|k| !self.seen(at, t + k as f32 * 0.25, crouching, walls))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::level::Level;
    use heist_shared::protocol::GuardId;

    fn routes(level: &Level) -> Vec<Vec<Vec2>> {
        level.guards.iter().map(|g| g.route.clone()).collect()
    }

    fn guard(at: Vec2, facing: f32) -> GuardView {
        GuardView { id: GuardId(0), name: "Bruno".into(), position: at, facing, alert: GuardAlert::Patrolling }
    }

    #[test]
    fn a_patrolling_guard_is_replayed_along_its_route() {
        let level = Level::museum();
        let route = level.guards[0].route.clone();
        let g = guard(route[0], 0.0);
        let f = Forecast::new(&GuardTuning::default(), &routes(&level), &[&g], 0, Vec2::ZERO);
        let (p, facing) = f.pose(0, 2.0);
        assert!((p - (route[0] + (route[1] - route[0]).normalize() * 2.2)).length() < 1e-3, "{p:?}");
        assert!(facing.is_some());
    }

    #[test]
    fn a_spot_behind_a_walking_guard_is_hidden_but_one_ahead_is_not() {
        let level = Level::museum();
        let walls = WallSet::new(&level);
        let route = level.guards[0].route.clone();
        let g = guard(route[0] + Vec2::new(4.0, 0.0), 0.0); // walking +x along the gallery
        let f = Forecast::new(&GuardTuning::default(), &routes(&level), &[&g], 0, Vec2::ZERO);
        assert!(f.seen(g.position + Vec2::new(4.0, 0.0), 0.0, false, &walls));
        assert!(!f.seen(g.position - Vec2::new(4.0, 0.0), 0.0, false, &walls));
    }
}
