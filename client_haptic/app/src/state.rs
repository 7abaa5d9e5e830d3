//! What the Phantom client remembers, one resource for each job: the lobby's greeting and menu
//! ([`Menu`]), the copy on the workbench and the verdicts given ([`Workbench`]), where the keys hold the
//! simulated hand ([`HandSteering`]). A new round forgets what belonged to the last one.

use bevy::prelude::*;
use glam::Vec3;
use heist_shared::artifact::{ArtifactKind, MaterialClass};
use heist_shared::protocol::ItemId;

use crate::explore::{Exploration, Findings};

/// The lobby: whether Phantom was greeted, briefed and said ready, and which menu item was read last.
#[derive(Resource, Default, Debug)]
pub struct Menu {
    /// The welcome was said.
    pub greeted: bool,
    /// This round's briefing was said.
    pub briefed: bool,
    /// Ready was sent to the server.
    pub ready_sent: bool,
    /// The menu item read last (an index of `status::MenuItem::ALL`).
    pub item: usize,
}

impl Menu {
    /// A rematch began: the greeting and the menu item stay; the new round is briefed afresh, and
    /// asking for it counted as being ready.
    pub fn new_round(&mut self) {
        self.briefed = false;
        self.ready_sent = true;
    }
}

/// What one verdict was based on.
#[derive(Clone, Debug, PartialEq)]
pub struct VerdictRecord {
    /// The copy.
    pub item: ItemId,
    /// Declared real.
    pub real: bool,
    /// What touch found (bot only).
    pub findings: Option<Findings>,
}

/// The copy on the workbench, the touch bot's exploration of it, and every verdict given this round.
#[derive(Resource, Default, Debug)]
pub struct Workbench {
    /// The copy on the bench and its kind (from the replicated item, never its data).
    pub copy: Option<(ItemId, Option<ArtifactKind>)>,
    /// The copy's material class, for the contact sound only.
    pub feel: Option<MaterialClass>,
    /// A copy arrived this frame (of this kind, if known): said after this frame's events, so the
    /// answer to the last verdict comes before the next copy.
    pub arrived: Option<Option<ArtifactKind>>,
    /// The touch bot's exploration of the copy, while it explores.
    pub exploration: Option<Exploration>,
    /// The last verdict sent: which copy, and whether it was declared real.
    pub last_verdict: Option<(ItemId, bool)>,
    /// The copy the touch bot judged last.
    pub judged: Option<ItemId>,
    /// Every verdict given.
    pub verdicts: Vec<VerdictRecord>,
}

impl Workbench {
    /// True while the haptic side is busy with a copy in real time (a tree building or the bot
    /// exploring): a test stepping the clock by hand should keep to wall-clock time meanwhile.
    pub fn busy(&self) -> bool {
        self.exploration.is_some() || self.copy.is_some_and(|c| self.judged != Some(c.0))
    }

    /// The copy held on the bench now (placed and feelable), if any: `holds` says whether the haptic
    /// side holds an item.
    pub fn held(&self, holds: impl Fn(ItemId) -> bool) -> Option<ItemId> {
        self.copy.map(|c| c.0).filter(|item| holds(*item))
    }

    /// Records a verdict given.
    pub fn give(&mut self, item: ItemId, real: bool, findings: Option<Findings>) {
        self.last_verdict = Some((item, real));
        self.verdicts.push(VerdictRecord { item, real, findings });
    }
}

/// Where the keys hold the simulated hand (the sim device), scene frame, metres: set by the first key
/// that moves it.
#[derive(Resource, Default, Debug)]
pub struct HandSteering {
    /// The hand's target, once a key moved it.
    pub target: Option<Vec3>,
}

impl HandSteering {
    /// Where the hand starts when a key first moves it, metres: above the bench, in front of the copy.
    pub const START: Vec3 = Vec3::new(0.0, 0.06, 0.07);
    /// How far from the bench's centre the keys move the hand at most, metres (each axis).
    pub const REACH_M: f32 = 0.12;
    /// How fast the keys move the hand, m/s.
    pub const SPEED_M_PER_S: f32 = 0.1;

    /// Moves the target along `direction` (a sum of unit axes) for `dt` seconds, within reach; the new
    /// target.
    pub fn push(&mut self, direction: Vec3, dt: f32) -> Vec3 {
        let at = *self.target.get_or_insert(Self::START);
        let next =
            (at + direction * Self::SPEED_M_PER_S * dt).clamp(Vec3::splat(-Self::REACH_M), Vec3::splat(Self::REACH_M));
        self.target = Some(next);
        next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_round_keeps_the_greeting_and_the_menu_and_briefs_again() {
        let mut menu = Menu { greeted: true, briefed: true, ready_sent: false, item: 3 };
        menu.new_round();
        assert!(menu.greeted && menu.ready_sent && !menu.briefed);
        assert_eq!(menu.item, 3);
    }

    #[test]
    fn the_keys_move_the_hand_from_above_the_bench_and_never_out_of_reach() {
        let mut hand = HandSteering::default();
        let first = hand.push(Vec3::X, 0.5);
        assert!((first - (HandSteering::START + Vec3::X * 0.05)).length() < 1e-6, "{first}");
        let far = hand.push(Vec3::new(1.0, 1.0, 0.0), 10.0);
        assert_eq!(far, Vec3::new(HandSteering::REACH_M, HandSteering::REACH_M, HandSteering::START.z));
    }

    #[test]
    fn the_bench_is_busy_until_its_copy_was_judged() {
        let mut bench = Workbench { copy: Some((ItemId(4), None)), ..Default::default() };
        assert!(bench.busy());
        assert_eq!(bench.held(|i| i == ItemId(4)), Some(ItemId(4)));
        assert_eq!(bench.held(|_| false), None, "placed but not yet feelable");
        bench.judged = Some(ItemId(4));
        assert!(!bench.busy());
        bench.give(ItemId(4), true, None);
        assert_eq!(bench.last_verdict, Some((ItemId(4), true)));
        assert_eq!(bench.verdicts.len(), 1);
    }
}
