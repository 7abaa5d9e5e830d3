//! Game-level intents: what the player wants this frame, whoever the player is.
//!
//! The headset's controllers ([`crate::xr`]), the keyboard and mouse ([`crate::desktop`]) and the bot
//! ([`crate::bot`]) all write one [`Intent`] per frame in [`IntentSystems::Gather`]; [`send`] turns it into
//! `ClientMsg`s for the server (which stays authoritative) and feeds the movement to the predictor.
//! [`Aim`] helps every input pick what an action is about (the case in front, the item within reach).

use bevy::prelude::*;
use glam::Vec2;
use heist_shared::protocol::{CaseId, CaseView, ClientMsg, Gait, ItemId, ItemPlace, ItemView, LobbyMsg, ViveMsg};
use heist_shared::rules;

/// One thing to do besides moving.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Say ready in the lobby.
    Ready,
    /// After a result: ask for another round.
    Rematch,
    /// Break a display case.
    Break(CaseId),
    /// Pick an item up.
    PickUp(ItemId),
    /// Put a carried item down at the feet.
    Drop(ItemId),
    /// Throw a carried item towards a floor point.
    Throw {
        /// The item.
        item: ItemId,
        /// Where it should land.
        target: Vec2,
    },
    /// Put a carried copy on Phantom's workbench.
    Place(ItemId),
}

impl Action {
    /// The message that asks the server for it.
    pub fn message(self) -> ClientMsg {
        match self {
            Action::Ready => ClientMsg::Lobby(LobbyMsg::Ready),
            Action::Rematch => ClientMsg::Lobby(LobbyMsg::Rematch),
            Action::Break(c) => ClientMsg::Vive(ViveMsg::Break(c)),
            Action::PickUp(i) => ClientMsg::Vive(ViveMsg::PickUp(i)),
            Action::Drop(i) => ClientMsg::Vive(ViveMsg::Drop(i)),
            Action::Throw { item, target } => ClientMsg::Vive(ViveMsg::Throw { item, target }),
            Action::Place(i) => ClientMsg::Vive(ViveMsg::PlaceOnWorkbench(i)),
        }
    }

    /// The intent a bot's (or a test's) `ViveMsg` stands for; `Move` is not an action.
    pub fn from_message(msg: &ViveMsg) -> Option<Self> {
        Some(match *msg {
            ViveMsg::Move { .. } | ViveMsg::WarningSeen(_) => return None,
            ViveMsg::Break(c) => Action::Break(c),
            ViveMsg::PickUp(i) => Action::PickUp(i),
            ViveMsg::Drop(i) => Action::Drop(i),
            ViveMsg::Throw { item, target } => Action::Throw { item, target },
            ViveMsg::PlaceOnWorkbench(i) => Action::Place(i),
        })
    }
}

/// What the player wants this frame.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct Intent {
    /// Direction on the museum floor, |d| ≤ 1 (zero stands still).
    pub movement: Vec2,
    /// How to move.
    pub gait: Gait,
    /// Where the body faces, radians on the floor (0 = +x, counter-clockwise).
    pub facing: f32,
    /// Actions this frame, in order.
    pub actions: Vec<Action>,
}

/// Which input drives the intents.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputSource {
    /// Headset and controllers.
    Xr,
    /// Keyboard and mouse.
    Desktop,
    /// The Vive bot.
    Bot,
}

/// System sets of the intent pipeline.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum IntentSystems {
    /// Clear last frame's movement (`RunFixedMainLoop`, before the fixed step).
    Clear,
    /// Inputs write the [`Intent`] (`RunFixedMainLoop`, before the fixed step — add input systems there).
    Gather,
    /// The intent goes to the server and the predictor (`FixedUpdate`, once per server tick).
    Send,
}

/// Server ticks an action waits for its answer before the very same action goes again (a second: a
/// round trip and a resend on a poor link); a refusal lets it go at once. A state seen a round trip late
/// would otherwise repeat it every tick, each repeat refused and counted against the client as abuse.
pub const ACTION_ANSWER_TICKS: u32 = 60;

/// Every message sent, counted, for tests and the log.
#[derive(Resource, Clone, Debug, Default)]
pub struct Sent {
    /// Last movement sequence number used.
    pub seq: u32,
    /// Actions sent, in order.
    pub actions: Vec<Action>,
    /// Actions held back as repeats of one awaiting its answer.
    pub repeats_held: u32,
    /// Sends so far (one per server tick).
    ticks: u32,
    /// Actions sent in the last [`ACTION_ANSWER_TICKS`] and the tick each went.
    awaiting: Vec<(Action, u32)>,
}

impl Sent {
    /// Whether `action` may go now (no identical one awaits its answer); if so, it is counted as awaiting.
    fn admit(&mut self, action: Action) -> bool {
        let now = self.ticks;
        self.awaiting.retain(|(_, at)| now.wrapping_sub(*at) < ACTION_ANSWER_TICKS);
        if self.awaiting.iter().any(|(a, _)| *a == action) {
            self.repeats_held += 1;
            return false;
        }
        self.awaiting.push((action, now));
        true
    }

    /// The server answered with a refusal: whatever awaited may be tried again at once.
    pub fn refused(&mut self) {
        self.awaiting.clear();
    }
}

/// Picks what an action is about, from where the player stands and looks.
pub struct Aim {
    /// Where the player (or the hand) is, on the floor.
    pub from: Vec2,
    /// Where the player looks (or the hand points), on the floor; any length.
    pub towards: Vec2,
}

impl Aim {
    /// How much a thing at `p` is "the one in front": within reach, the nearest to the line of sight.
    fn score(&self, p: Vec2) -> Option<f32> {
        let d = p - self.from;
        let dist = d.length();
        if dist > rules::REACH {
            return None;
        }
        let dir = self.towards.normalize_or_zero();
        let ahead = if dist < 1e-3 || dir == Vec2::ZERO { 1.0 } else { d.dot(dir) / dist };
        // Behind the player counts only when touching it.
        if ahead < -0.2 && dist > 0.6 {
            return None;
        }
        Some(dist * (2.0 - ahead))
    }

    /// The unbroken case to break.
    pub fn case<'a>(&self, cases: impl IntoIterator<Item = &'a CaseView>) -> Option<CaseId> {
        cases
            .into_iter()
            .filter(|c| !c.broken)
            .filter_map(|c| self.score(c.position).map(|s| (s, c.id)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, id)| id)
    }

    /// The item to pick up: on the floor, or in a broken case.
    pub fn item<'a>(&self, items: impl IntoIterator<Item = &'a ItemView>, cases: &[&CaseView]) -> Option<ItemId> {
        items
            .into_iter()
            .filter_map(|i| {
                let at = match i.place {
                    ItemPlace::Floor(p) => p,
                    ItemPlace::InCase(c) => cases.iter().find(|cv| cv.id == c && cv.broken)?.position,
                    _ => return None,
                };
                self.score(at).map(|s| (s, i.id))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, id)| id)
    }

    /// Where a throw lands: along the aim, `distance` away, at most the throw range.
    pub fn throw_target(&self, distance: f32) -> Vec2 {
        self.from + self.towards.normalize_or(Vec2::X) * distance.clamp(1.0, rules::THROW_RANGE)
    }
}

/// Clears the movement at the start of the frame (the facing stays; actions wait for the next send).
pub fn clear(mut intent: ResMut<Intent>) {
    intent.movement = Vec2::ZERO;
    intent.gait = Gait::Walk;
}

/// Sends this frame's intent and predicts the body's movement (see the module docs).
pub fn send(
    mut intent: ResMut<Intent>,
    mut sent: ResMut<Sent>,
    mut out: MessageWriter<ClientMsg>,
    mut state: ResMut<crate::state::ViveState>,
) {
    sent.ticks = sent.ticks.wrapping_add(1);
    for action in intent.actions.drain(..) {
        if sent.admit(action) {
            out.write(action.message());
            sent.actions.push(action);
        }
    }
    if !state.in_heist() {
        return;
    }
    let direction = intent.movement.clamp_length_max(1.0);
    let direction = if direction.is_finite() { direction } else { Vec2::ZERO };
    let facing = if intent.facing.is_finite() { intent.facing } else { 0.0 };
    sent.seq += 1;
    out.write(ClientMsg::Vive(ViveMsg::Move { seq: sent.seq, direction, gait: intent.gait, facing }));
    // Each input is worth one server tick.
    let dt = (1.0 / heist_shared::protocol::TICK_HZ) as f32;
    if let Some(p) = state.predictor.as_mut() {
        p.apply(sent.seq, direction, rules::gait_speed(intent.gait), dt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(id: u16, x: f32, y: f32, broken: bool) -> CaseView {
        CaseView { id: CaseId(id), position: Vec2::new(x, y), broken }
    }

    #[test]
    fn the_case_in_front_is_chosen_over_the_one_behind() {
        let cases = [case(0, -1.0, 0.0, false), case(1, 1.2, 0.1, false), case(2, 0.5, 0.0, true)];
        let aim = Aim { from: Vec2::ZERO, towards: Vec2::X };
        assert_eq!(aim.case(&cases), Some(CaseId(1)));
        let aim = Aim { from: Vec2::ZERO, towards: -Vec2::X };
        assert_eq!(aim.case(&cases), Some(CaseId(0)));
        let aim = Aim { from: Vec2::new(10.0, 0.0), towards: Vec2::X };
        assert_eq!(aim.case(&cases), None, "nothing within reach");
    }

    #[test]
    fn items_are_taken_from_the_floor_or_broken_cases_only() {
        let cases = [case(0, 1.0, 0.0, false), case(1, 0.0, 1.0, true)];
        let refs: Vec<&CaseView> = cases.iter().collect();
        let item = |id: u16, place| ItemView { id: ItemId(id), kind: heist_shared::protocol::ItemKind::Prop, place };
        let items =
            [item(0, ItemPlace::InCase(CaseId(0))), item(1, ItemPlace::InCase(CaseId(1))), item(2, ItemPlace::Carried)];
        let aim = Aim { from: Vec2::ZERO, towards: Vec2::X };
        assert_eq!(aim.item(&items, &refs), Some(ItemId(1)), "the closed case's copy is out of the hand's way");
        let on_floor = [item(3, ItemPlace::Floor(Vec2::new(0.5, 0.0)))];
        assert_eq!(aim.item(&on_floor, &refs), Some(ItemId(3)));
    }

    #[test]
    fn throws_land_along_the_aim_within_range() {
        let aim = Aim { from: Vec2::new(1.0, 1.0), towards: Vec2::new(0.0, 2.0) };
        assert_eq!(aim.throw_target(5.0), Vec2::new(1.0, 6.0));
        assert_eq!(aim.throw_target(50.0), Vec2::new(1.0, 1.0 + rules::THROW_RANGE));
    }

    #[test]
    fn an_action_awaiting_its_answer_is_not_repeated_until_a_second_passed_or_a_refusal_came() {
        let mut sent = Sent::default();
        let brk = Action::Break(CaseId(1));
        assert!(sent.admit(brk));
        assert!(!sent.admit(brk), "the same action again at once is held back");
        assert!(sent.admit(Action::PickUp(ItemId(2))), "another action goes");
        for _ in 0..ACTION_ANSWER_TICKS - 1 {
            sent.ticks += 1;
        }
        assert!(!sent.admit(brk), "still awaiting");
        sent.ticks += 1;
        assert!(sent.admit(brk), "a second later it may go again");
        sent.refused();
        assert!(sent.admit(brk), "a refusal lets it go at once");
        assert_eq!(sent.repeats_held, 2);
    }

    #[test]
    fn every_action_round_trips_through_its_message() {
        let actions = [
            Action::Break(CaseId(2)),
            Action::PickUp(ItemId(1)),
            Action::Drop(ItemId(1)),
            Action::Throw { item: ItemId(4), target: Vec2::new(1.0, 2.0) },
            Action::Place(ItemId(3)),
        ];
        for a in actions {
            let ClientMsg::Vive(msg) = a.message() else { panic!("{a:?} is a Vive message") };
            assert_eq!(Action::from_message(&msg), Some(a));
        }
    }
}
