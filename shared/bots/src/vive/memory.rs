//! What the Vive bot remembers from frame to frame: its clock, the way it is walking, how long it has
//! waited, where it fled to, which item it is after and which it gave up on for now, where it has been,
//! and each guard as last seen. Apart from the [`super::map::Map`], which never changes.

use std::collections::VecDeque;

use crate::forecast::{Forecast, Known, Noise};
use crate::spacetime::Timed;
use glam::Vec2;
use heist_shared::level::{Level, NavGraph, patrol};
use heist_shared::protocol::{Gait, GuardView, ItemId};
use heist_shared::protocol::{GuardAlert, GuardId, RadioAbout};
use heist_shared::rules::GuardTuning;

/// Seconds an alerted guard out of sight is imagined where it was last seen; after that it is
/// imagined back on its patrol.
const ALERT_MEMORY_S: f32 = 8.0;
/// A searching guard seen this close to one of his spots has searched it, metres.
const SPOT_VISITED_M: f32 = 1.0;
/// Positions kept of where the bot has been (one a frame): hiding places it knows are reachable.
const TRAIL_LEN: usize = 900;

#[derive(Default)]
pub(crate) struct Memory {
    /// Heist time as the bot counts it, seconds.
    pub clock_s: f32,
    /// The way to the current target, last waypoint first.
    pub route: Vec<Vec2>,
    /// The target `route` leads to.
    pub route_goal: Option<Vec2>,
    /// The timed way (space and time) it is carrying out, if any.
    pub timed: Option<Timed>,
    /// Where the timed way says to head this frame, and at which gait.
    pub step: Option<(Vec2, Gait)>,
    /// Progress towards the goal: (goal, the closest the bot has come to it, when it last came a metre
    /// closer). Waiting and hiding make none; a frame's step forward and back again does not count.
    pub progress: Option<(Vec2, f32, f32)>,
    /// Seconds spent waiting at a case for the guards to get out of earshot.
    pub break_waited_s: f32,
    /// Since when the case at hand has been out of every guard's earshot.
    pub quiet_since: Option<f32>,
    /// When the bot last threw something to lure a guard.
    pub lured_at: Option<f32>,
    /// When the bot last saw a guard chasing it.
    pub chased_at: Option<f32>,
    /// Where the bot is fleeing to, and when it chose it.
    pub refuge: Option<(Vec2, f32)>,
    /// The item the bot is going for.
    pub committed: Option<ItemId>,
    /// Items given up on until a time (the way to them was watched too long).
    pub avoid: Vec<(ItemId, f32)>,
    /// Where the bot has been, oldest first.
    pub trail: VecDeque<Vec2>,
    /// Noises the bot made (glass it broke, props it threw: where, and when), the last few seconds:
    /// a guard who comes to look is coming to one of them.
    pub noises: Vec<Noise>,
    /// The spots each guard was radioed to search (by guard id), those he has not yet been seen at:
    /// worked out from the call as the server does (`heist_shared::level::patrol::orders`).
    pub searches: Vec<(GuardId, Vec<Vec2>)>,
    /// Each guard as last seen and when (the server sends only guards Vive can perceive).
    pub remembered: Vec<(GuardView, f32)>,
}

impl Memory {
    /// Hears a radio call: the guards answering it will search their share of the spots around `at`.
    pub fn heard_radio(&mut self, nav: &NavGraph, about: RadioAbout, at: Vec2, answering: &[GuardId]) {
        if about == RadioAbout::Evidence {
            // That glass is reported: nobody will radio about it again.
            for n in self.noises.iter_mut().filter(|n| n.at.distance(at) < 0.5) {
                n.evidence = false;
            }
        }
        for (&id, spots) in answering.iter().zip(patrol::orders(nav, at, about.search_spots(), answering.len())) {
            self.searches.retain(|(g, _)| *g != id);
            self.searches.push((id, spots));
        }
    }

    /// Remembers the guards in sight now (and crosses off the search spots they are seen at, and the
    /// searches of those back on their rounds).
    pub fn see(&mut self, guards: &[&GuardView]) {
        for g in guards {
            if let Some((_, spots)) = self.searches.iter_mut().find(|(id, _)| *id == g.id) {
                spots.retain(|s| s.distance(g.position) > SPOT_VISITED_M);
            }
            if matches!(g.alert, GuardAlert::Patrolling | GuardAlert::Returning) {
                self.searches.retain(|(id, _)| *id != g.id);
            }
        }
        self.searches.retain(|(_, spots)| !spots.is_empty());
        for g in guards {
            self.remembered.retain(|(r, _)| r.id != g.id);
            self.remembered.push(((*g).clone(), self.clock_s));
        }
    }

    /// Learns the guards on duty before the heist starts, as any player can from the level: each one at
    /// the start of his round, walking to its second waypoint (until seen, each is imagined along it).
    pub fn brief(&mut self, level: &Level, tuning: &GuardTuning) {
        let on_duty = level.guards.iter().take(tuning.guards.unwrap_or(usize::MAX)).enumerate();
        for (i, g) in on_duty.filter(|(_, g)| !g.route.is_empty()) {
            let id = GuardId(i as u16);
            if self.remembered.iter().any(|(r, _)| r.id == id) {
                continue;
            }
            let (start, next) = (g.route[0], g.route.get(1).copied().unwrap_or(g.route[0]));
            let facing = (next - start).to_angle();
            let view = GuardView { id, name: g.name.clone(), position: start, facing, alert: GuardAlert::Patrolling };
            self.remembered.push((view, self.clock_s));
        }
    }

    /// The guards out of sight, imagined where they have likely walked since they were last seen.
    pub fn imagined(&self, in_sight: &[&GuardView], known: &Known<'_>) -> Vec<GuardView> {
        self.remembered
            .iter()
            .filter(|(r, _)| !in_sight.iter().any(|g| g.id == r.id))
            .map(|(r, at)| Forecast::imagine(known, r, self.clock_s - at, ALERT_MEMORY_S))
            .collect()
    }

    /// Notes where the bot is (bounded).
    pub fn walked(&mut self, at: Vec2) {
        if self.trail.len() == TRAIL_LEN {
            self.trail.pop_front();
        }
        self.trail.push_back(at);
    }

    /// Notes how close the bot is to `goal` now.
    pub fn approach(&mut self, goal: Vec2, at: Vec2) {
        let d = goal.distance(at);
        match &mut self.progress {
            Some((g, best, since)) if g.distance(goal) < 0.3 => {
                if d < *best - 1.0 {
                    (*best, *since) = (d, self.clock_s);
                }
            }
            _ => self.progress = Some((goal, d, self.clock_s)),
        }
    }

    /// Seconds since the bot last came a metre closer to its goal.
    pub fn stalled_s(&self) -> f32 {
        self.progress.map_or(0.0, |(_, _, since)| self.clock_s - since)
    }

    /// True while `item` is given up on.
    pub fn avoids(&self, item: ItemId) -> bool {
        self.avoid.iter().any(|(a, until)| *a == item && *until > self.clock_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::rules;

    #[test]
    fn a_radio_call_gives_each_answering_guard_the_spots_the_server_gives_him_crossed_off_as_seen() {
        let level = heist_shared::level::Level::museum();
        let nav = NavGraph::new(&level);
        let at = Vec2::new(20.0, 5.0);
        let mut m = Memory::default();
        m.heard_radio(&nav, RadioAbout::Sighting, at, &[GuardId(1), GuardId(2)]);
        let orders = patrol::orders(&nav, at, rules::SEARCH_SPOTS, 2);
        assert_eq!(m.searches, vec![(GuardId(1), orders[0].clone()), (GuardId(2), orders[1].clone())]);
        let first = orders[0][0];
        let seen = |id: u16, position: Vec2, alert: GuardAlert| GuardView {
            id: GuardId(id),
            name: String::new(),
            position,
            facing: 0.0,
            alert,
        };
        m.see(&[&seen(1, first, GuardAlert::Searching)]);
        assert_eq!(m.searches[0].1, orders[0][1..].to_vec(), "the spot he was seen at is searched");
        m.see(&[&seen(2, Vec2::ZERO, GuardAlert::Returning)]);
        assert!(m.searches.iter().all(|(id, _)| *id != GuardId(2)), "back to his round: his search is over");
        m.heard_radio(&nav, RadioAbout::Evidence, at, &[GuardId(1)]);
        assert_eq!(m.searches, vec![(GuardId(1), patrol::orders(&nav, at, rules::EVIDENCE_SPOTS, 1)[0].clone())]);
    }

    #[test]
    fn glass_the_bot_broke_stays_evidence_until_a_guard_radios_that_he_found_it() {
        let nav = NavGraph::new(&heist_shared::level::Level::museum());
        let (case, other) = (Vec2::new(28.0, 20.8), Vec2::new(13.0, 1.2));
        let glass = |at| Noise { at, when_s: 0.0, loudness: rules::GLASS_LOUDNESS, evidence: true };
        let mut m = Memory { noises: vec![glass(case), glass(other)], ..Default::default() };
        m.heard_radio(&nav, RadioAbout::Sighting, case, &[GuardId(1)]);
        assert!(m.noises.iter().all(|n| n.evidence), "a sighting reports no glass");
        m.heard_radio(&nav, RadioAbout::Evidence, case, &[GuardId(1)]);
        assert_eq!(m.noises.iter().map(|n| n.evidence).collect::<Vec<_>>(), vec![false, true]);
    }

    #[test]
    fn before_a_guard_is_ever_seen_each_one_on_duty_is_imagined_along_his_round_from_its_start() {
        let level = heist_shared::level::Level::museum();
        let nav = NavGraph::new(&level);
        let easy = heist_shared::rules::Difficulty::Easy.tuning(); // two guards on duty
        let mut m = Memory::default();
        m.brief(&level, &easy);
        assert_eq!(m.remembered.len(), 2);
        let (bruno, _) = &m.remembered[0];
        assert_eq!(
            (bruno.position, bruno.facing, bruno.alert),
            (level.guards[0].route[0], 0.0, GuardAlert::Patrolling)
        );
        // Ten seconds in, never seen: imagined ten seconds' walk along his round.
        m.clock_s = 10.0;
        let routes: Vec<Vec<Vec2>> = level.guards.iter().map(|g| g.route.clone()).collect();
        let known = Known { tuning: &easy, nav: &nav, routes: &routes, alarm: 0 };
        let imagined = m.imagined(&[], &known);
        let walked = imagined[0].position.distance(level.guards[0].route[0]);
        assert!((walked - 10.0 * easy.patrol_speed).abs() < 0.05, "walked {walked} m");
        // Seen once, a guard is remembered as seen, not as briefed.
        let clara = GuardView { position: Vec2::new(17.0, 15.0), ..m.remembered[1].0.clone() };
        m.see(&[&clara]);
        m.brief(&level, &easy);
        assert_eq!(m.remembered.len(), 2, "briefing again adds nobody");
        assert!(m.remembered.iter().any(|(g, at)| g.position == clara.position && *at == 10.0));
    }

    #[test]
    fn stepping_forth_and_back_is_no_progress_but_a_metre_closer_is() {
        let mut m = Memory::default();
        let goal = Vec2::new(10.0, 0.0);
        m.approach(goal, Vec2::ZERO);
        for k in 0..100 {
            m.clock_s += 0.1;
            m.approach(goal, Vec2::new(if k % 2 == 0 { 0.5 } else { 0.0 }, 0.0));
        }
        assert!((m.stalled_s() - 10.0).abs() < 1e-3, "dithering for 10 s: stalled {}", m.stalled_s());
        m.approach(goal, Vec2::new(1.5, 0.0));
        assert_eq!(m.stalled_s(), 0.0, "a metre closer");
        m.clock_s += 1.0;
        m.approach(Vec2::new(0.0, 20.0), Vec2::new(1.5, 0.0));
        assert_eq!(m.stalled_s(), 0.0, "a new goal starts afresh");
    }

    #[test]
    fn the_trail_keeps_the_latest_places_only_and_given_up_items_come_back_in_time() {
        let mut m = Memory::default();
        for i in 0..(TRAIL_LEN + 10) {
            m.walked(Vec2::new(i as f32, 0.0));
        }
        assert_eq!(m.trail.len(), TRAIL_LEN);
        assert_eq!(m.trail.front(), Some(&Vec2::new(10.0, 0.0)));
        m.avoid.push((ItemId(3), 5.0));
        assert!(m.avoids(ItemId(3)) && !m.avoids(ItemId(4)));
        m.clock_s = 6.0;
        assert!(!m.avoids(ItemId(3)));
    }
}
