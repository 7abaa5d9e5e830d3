//! The guards' radio. A call goes out at once — both players hear it — and reaches the guards within the
//! tuning's range of the caller after its delay; each guard who answers gets his share of the spots to
//! search around where the call was about, so the searchers split up.
//!
//! You need this module to change who hears a call, and when. Plain data stepped by the game's clock.

use glam::Vec2;
use heist_shared::rules::GuardTuning;

use super::guard::Guard;

/// A call on its way.
#[derive(Clone, Debug, PartialEq)]
struct Call {
    due_s: f32,
    at: Vec2,
    spots: usize,
    answering: Vec<usize>,
}

/// Calls made and not yet heard.
#[derive(Clone, Debug, Default)]
pub struct Radio {
    pending: Vec<Call>,
}

/// Calls waiting at most (a guard radios once per cooldown; this bounds the queue whatever happens).
const MAX_PENDING: usize = 32;

impl Radio {
    /// Guard `caller` radios about `at` at game time `now`, asking for `spots` spots around it to be
    /// searched: returns the guards (indices) who will answer, nearest to `at` first — every other guard
    /// within `t.radio_range_m` of the caller (none on a tuning without radio).
    pub fn call(
        &mut self,
        guards: &[Guard],
        caller: usize,
        (at, spots): (Vec2, usize),
        t: &GuardTuning,
        now: f32,
    ) -> Vec<usize> {
        let Some(from) = guards.get(caller).map(|g| g.position) else { return Vec::new() };
        if t.radio_range_m <= 0.0 {
            return Vec::new();
        }
        let mut answering: Vec<usize> = (0..guards.len())
            .filter(|&i| i != caller && guards[i].position.distance(from) <= t.radio_range_m)
            .collect();
        answering.sort_by(|&a, &b| guards[a].position.distance(at).total_cmp(&guards[b].position.distance(at)));
        if !answering.is_empty() && self.pending.len() < MAX_PENDING {
            self.pending.push(Call { due_s: now + t.radio_delay_s, at, spots, answering: answering.clone() });
        }
        answering
    }

    /// The calls heard by `now`, oldest first: (the guards who answer, where, how many spots to search).
    pub fn heard(&mut self, now: f32) -> Vec<(Vec<usize>, Vec2, usize)> {
        let (due, later): (Vec<Call>, Vec<Call>) = self.pending.drain(..).partition(|c| c.due_s <= now);
        self.pending = later;
        due.into_iter().map(|c| (c.answering, c.at, c.spots)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::GuardId;

    fn guard_at(i: u16, p: Vec2) -> Guard {
        Guard::new(GuardId(i), format!("G{i}"), vec![p, p + Vec2::X])
    }

    #[test]
    fn a_call_reaches_the_guards_within_range_after_the_delay_nearest_to_the_spot_first() {
        let guards = vec![
            guard_at(0, Vec2::ZERO),
            guard_at(1, Vec2::new(30.0, 0.0)),
            guard_at(2, Vec2::new(10.0, 0.0)),
            guard_at(3, Vec2::new(100.0, 0.0)),
        ];
        let t = GuardTuning { radio_range_m: 40.0, radio_delay_s: 2.0, ..Default::default() };
        let mut radio = Radio::default();
        let answering = radio.call(&guards, 0, (Vec2::new(12.0, 0.0), 4), &t, 5.0);
        assert_eq!(answering, vec![2, 1], "guard 3 is out of range; the caller does not answer himself");
        assert!(radio.heard(6.9).is_empty(), "not before the delay");
        assert_eq!(radio.heard(7.0), vec![(vec![2, 1], Vec2::new(12.0, 0.0), 4)]);
        assert!(radio.heard(8.0).is_empty(), "heard once");
    }

    #[test]
    fn without_radio_nobody_answers() {
        let guards = vec![guard_at(0, Vec2::ZERO), guard_at(1, Vec2::X)];
        let t = GuardTuning { radio_range_m: 0.0, ..Default::default() };
        let mut radio = Radio::default();
        assert!(radio.call(&guards, 0, (Vec2::ZERO, 4), &t, 0.0).is_empty());
        assert!(radio.heard(100.0).is_empty());
    }
}
