//! How the Vive bot moves towards its goal, as small named decisions tried in order (the first that
//! applies wins), like the guards' own (`server/src/game/guard`). Each looks only at the
//! [`Perception`] — everything worth knowing this frame, worked out beforehand from what a player could
//! know — so each is a pure function tested on its own.

use glam::Vec2;
use heist_shared::protocol::{Gait, ItemId, ViveMsg};

/// Seconds the bot waits unseen for a guard to move before throwing something to lure it away.
pub(crate) const LURE_AFTER_S: f32 = 4.0;
/// Seconds of waiting for one goal after which the bot gives it up for a while and tries another.
pub(crate) const GIVE_UP_AFTER_S: f32 = 25.0;
/// Seconds the bot waits at a case for the guards to get out of earshot before giving that item up
/// for a while (it never breaks glass a guard would hear).
pub(crate) const BREAK_PATIENCE_S: f32 = 12.0;

/// Seconds the case must have been out of earshot before the bot breaks it.
pub(crate) const QUIET_BEFORE_BREAK_S: f32 = 1.0;

/// What the bot knows this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Perception {
    /// Plays recklessly: straight for the goal, running, guards or not.
    pub reckless: bool,
    /// A guard is chasing Vive (or was a moment ago).
    pub chased: bool,
    /// A guard sees (or could see) Vive where he stands, or stands too close for comfort.
    pub exposed: bool,
    /// Vive is within reach of the goal.
    pub at_goal: bool,
    /// What to do at the goal, once in reach (`None`: nothing now, e.g. the workbench is taken).
    pub action: Option<ViveMsg>,
    /// A guard would hear the glass if Vive broke the case of the goal here now, and be there too soon
    /// for Vive to grab the copy and get away.
    pub break_heard: bool,
    /// Seconds the case has been out of every guard's earshot (a break waits for a settled quiet).
    pub quiet_s: f32,
    /// The timed way (`crate::spacetime`) says: step on now, at this gait (running only out of
    /// earshot). At the goal: leave it, a guard will see this spot.
    pub way: Option<Gait>,
    /// The timed way says: wait here, crouching, for the way ahead to clear.
    pub hold: bool,
    /// Standing (crouching) here stays unseen for the next seconds.
    pub hidden_here: bool,
    /// A carried prop and where to throw it so it draws the nearest guard away, when a lure is due.
    pub lure: Option<(ItemId, Vec2)>,
    /// Seconds since the bot last came a metre closer to its goal.
    pub waited_s: f32,
    /// Seconds spent waiting at the case for quiet.
    pub break_waited_s: f32,
    /// The goal is an item (so giving it up means something).
    pub fetching: bool,
}

impl Perception {
    fn breaking(&self) -> bool {
        matches!(self.action, Some(ViveMsg::Break(_)))
    }
}

/// What the bot does this frame.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Plan {
    /// Walk the way to the goal at this gait.
    Go(Gait),
    /// Do this (in reach of the goal).
    Act(ViveMsg),
    /// Crouch where it stands.
    Wait,
    /// Move to the nearest spot it can reach unseen that stays hidden.
    Hide,
    /// Run for the refuge that keeps it furthest ahead of every guard.
    Flee,
    /// Throw this prop at that point.
    Throw(ItemId, Vec2),
    /// Give the goal's item up for a while and choose another.
    GiveUp,
}

/// Reckless play: run straight at the goal and act at once.
fn rush_if_reckless(p: &Perception) -> Option<Plan> {
    if !p.reckless {
        return None;
    }
    Some(match (&p.action, p.at_goal) {
        (Some(a), true) => Plan::Act(a.clone()),
        (None, true) => Plan::Wait,
        _ => Plan::Go(Gait::Run),
    })
}

/// Chased: run for the place we reach furthest ahead of every guard, and hope it loses sight.
fn flee_if_chased(p: &Perception) -> Option<Plan> {
    p.chased.then_some(Plan::Flee)
}

/// Seen, or about to be: get out of sight first.
fn hide_if_seen_soon(p: &Perception) -> Option<Plan> {
    p.exposed.then_some(Plan::Hide)
}

/// In reach of something quiet to do (pick up, place on the bench): do it.
fn act_if_in_reach(p: &Perception) -> Option<Plan> {
    match &p.action {
        Some(a) if p.at_goal && !p.breaking() => Some(Plan::Act(a.clone())),
        _ => None,
    }
}

/// At the goal but a guard will see this spot soon, and the timed way leads away: go (and come back).
fn leave_goal_if_watched(p: &Perception) -> Option<Plan> {
    p.way.filter(|_| p.at_goal).map(Plan::Go)
}

/// At the case and no guard would hear the glass (for a settled moment, not one hopeful frame): break it.
fn break_if_unheard(p: &Perception) -> Option<Plan> {
    match &p.action {
        Some(a) if p.at_goal && p.breaking() && !p.break_heard && p.quiet_s >= QUIET_BEFORE_BREAK_S => {
            Some(Plan::Act(a.clone()))
        }
        _ => None,
    }
}

/// At the case with a guard in earshot, and a prop in hand: throw it to draw him further away.
fn lure_if_break_heard(p: &Perception) -> Option<Plan> {
    let (item, at) = p.lure?;
    (p.at_goal && p.breaking() && p.break_heard).then_some(Plan::Throw(item, at))
}

/// At the case and waited long enough for quiet: leave it for now, try another item.
fn give_up_if_break_heard_too_long(p: &Perception) -> Option<Plan> {
    (p.at_goal && p.breaking() && p.break_waited_s > BREAK_PATIENCE_S).then_some(Plan::GiveUp)
}

/// At the goal with nothing to do yet (a guard in earshot, the bench taken): wait, crouching.
fn wait_if_at_goal(p: &Perception) -> Option<Plan> {
    p.at_goal.then_some(Plan::Wait)
}

/// The timed way says step on: go, at its gait.
fn go_if_way_hidden(p: &Perception) -> Option<Plan> {
    p.way.map(Plan::Go)
}

/// Waiting hidden for a guard who blocks the way, with a prop in hand: throw it past him.
fn lure_if_blocked(p: &Perception) -> Option<Plan> {
    let (item, at) = p.lure?;
    (p.hidden_here && p.waited_s > LURE_AFTER_S).then_some(Plan::Throw(item, at))
}

/// No metre closer to the item for too long (the way watched, or every way round it too): give it up
/// for a while.
fn give_up_if_stuck(p: &Perception) -> Option<Plan> {
    (p.fetching && p.waited_s > GIVE_UP_AFTER_S).then_some(Plan::GiveUp)
}

/// The timed way waits here for a guard to pass: wait.
fn wait_if_way_timed(p: &Perception) -> Option<Plan> {
    p.hold.then_some(Plan::Wait)
}

/// The way is watched but here is safe: wait for it to clear.
fn wait_if_hidden(p: &Perception) -> Option<Plan> {
    p.hidden_here.then_some(Plan::Wait)
}

/// Neither the way nor here is safe: find a better hiding place.
fn hide_otherwise(_p: &Perception) -> Option<Plan> {
    Some(Plan::Hide)
}

/// A decision: its name (for the time-spent tally) and the rule.
pub(crate) type Decision = (&'static str, fn(&Perception) -> Option<Plan>);

/// The decisions in priority order.
pub(crate) const DECISIONS: &[Decision] = &[
    ("rush_if_reckless", rush_if_reckless),
    ("flee_if_chased", flee_if_chased),
    ("hide_if_seen_soon", hide_if_seen_soon),
    ("act_if_in_reach", act_if_in_reach),
    ("leave_goal_if_watched", leave_goal_if_watched),
    ("break_if_unheard", break_if_unheard),
    ("lure_if_break_heard", lure_if_break_heard),
    ("give_up_if_break_heard_too_long", give_up_if_break_heard_too_long),
    ("wait_if_at_goal", wait_if_at_goal),
    ("give_up_if_stuck", give_up_if_stuck),
    ("go_if_way_hidden", go_if_way_hidden),
    ("lure_if_blocked", lure_if_blocked),
    ("wait_if_way_timed", wait_if_way_timed),
    ("wait_if_hidden", wait_if_hidden),
    ("hide_otherwise", hide_otherwise),
];

/// The first decision that applies: its index in [`DECISIONS`] and the plan.
pub(crate) fn decide(p: &Perception) -> (usize, Plan) {
    DECISIONS
        .iter()
        .enumerate()
        .find_map(|(i, (_, f))| f(p).map(|plan| (i, plan)))
        .unwrap_or((DECISIONS.len() - 1, Plan::Hide))
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::CaseId;

    fn named(p: &Perception) -> (&'static str, Plan) {
        let (i, plan) = decide(p);
        (DECISIONS[i].0, plan)
    }

    fn at_case() -> Perception {
        Perception {
            at_goal: true,
            action: Some(ViveMsg::Break(CaseId(3))),
            fetching: true,
            quiet_s: QUIET_BEFORE_BREAK_S,
            ..Default::default()
        }
    }

    const PROP: (ItemId, Vec2) = (ItemId(9), Vec2::new(20.0, 4.0));

    #[test]
    fn a_reckless_bot_runs_at_its_goal_even_when_chased_and_acts_on_arrival() {
        let p = Perception { reckless: true, chased: true, exposed: true, ..Default::default() };
        assert_eq!(named(&p), ("rush_if_reckless", Plan::Go(Gait::Run)));
        let there = Perception { reckless: true, break_heard: true, ..at_case() };
        assert_eq!(named(&there), ("rush_if_reckless", Plan::Act(ViveMsg::Break(CaseId(3)))));
    }

    #[test]
    fn a_chased_bot_flees_before_anything_else() {
        let p = Perception { chased: true, exposed: true, ..at_case() };
        assert_eq!(named(&p), ("flee_if_chased", Plan::Flee));
    }

    #[test]
    fn a_bot_about_to_be_seen_hides_even_in_reach_of_its_goal() {
        let p = Perception { exposed: true, ..at_case() };
        assert_eq!(named(&p), ("hide_if_seen_soon", Plan::Hide));
    }

    #[test]
    fn in_reach_a_quiet_action_is_done_at_once() {
        let p = Perception { at_goal: true, action: Some(ViveMsg::PickUp(ItemId(4))), ..Default::default() };
        assert_eq!(named(&p), ("act_if_in_reach", Plan::Act(ViveMsg::PickUp(ItemId(4)))));
    }

    #[test]
    fn a_case_is_broken_only_when_no_guard_would_hear_it() {
        assert_eq!(named(&at_case()), ("break_if_unheard", Plan::Act(ViveMsg::Break(CaseId(3)))));
        let heard = Perception { break_heard: true, ..at_case() };
        assert_eq!(named(&heard), ("wait_if_at_goal", Plan::Wait));
        let just_quiet = Perception { quiet_s: 0.1, ..at_case() };
        assert_eq!(named(&just_quiet), ("wait_if_at_goal", Plan::Wait), "one quiet frame is not enough");
    }

    #[test]
    fn a_guard_in_earshot_of_the_case_is_lured_away_with_a_prop_in_hand() {
        let p = Perception { break_heard: true, lure: Some(PROP), ..at_case() };
        assert_eq!(named(&p), ("lure_if_break_heard", Plan::Throw(PROP.0, PROP.1)));
    }

    #[test]
    fn after_waiting_too_long_for_quiet_the_item_is_given_up_for_a_while_never_broken_anyway() {
        let p = Perception { break_heard: true, break_waited_s: BREAK_PATIENCE_S + 0.1, ..at_case() };
        assert_eq!(named(&p), ("give_up_if_break_heard_too_long", Plan::GiveUp));
    }

    #[test]
    fn at_the_goal_with_nothing_to_do_yet_the_bot_waits() {
        let p = Perception { at_goal: true, action: None, ..Default::default() };
        assert_eq!(named(&p), ("wait_if_at_goal", Plan::Wait));
    }

    #[test]
    fn the_bot_steps_on_when_its_timed_way_says_so_at_its_gait() {
        let p = Perception {
            way: Some(Gait::Crouch),
            hidden_here: true,
            waited_s: GIVE_UP_AFTER_S - 1.0,
            fetching: true,
            ..Default::default()
        };
        assert_eq!(named(&p), ("go_if_way_hidden", Plan::Go(Gait::Crouch)));
    }

    #[test]
    fn no_closer_for_too_long_the_item_is_given_up_even_when_some_way_round_is_open() {
        // Going round and round (ways that open and close) is no progress either.
        let p =
            Perception { way: Some(Gait::Walk), waited_s: GIVE_UP_AFTER_S + 0.1, fetching: true, ..Default::default() };
        assert_eq!(named(&p), ("give_up_if_stuck", Plan::GiveUp));
        let delivering = Perception { fetching: false, ..p };
        assert_eq!(named(&delivering), ("go_if_way_hidden", Plan::Go(Gait::Walk)), "a copy in hand is never given up");
    }

    #[test]
    fn a_watched_way_is_waited_out_hidden_then_a_prop_is_thrown_then_the_item_given_up() {
        let p = Perception { hidden_here: true, fetching: true, ..Default::default() };
        assert_eq!(named(&p), ("wait_if_hidden", Plan::Wait));
        let long = Perception { waited_s: LURE_AFTER_S + 0.1, lure: Some(PROP), ..p.clone() };
        assert_eq!(named(&long), ("lure_if_blocked", Plan::Throw(PROP.0, PROP.1)));
        let longer = Perception { waited_s: GIVE_UP_AFTER_S + 0.1, ..p.clone() };
        assert_eq!(named(&longer), ("give_up_if_stuck", Plan::GiveUp));
        let not_fetching = Perception { fetching: false, ..longer };
        assert_eq!(named(&not_fetching), ("wait_if_hidden", Plan::Wait));
    }

    #[test]
    fn when_the_timed_way_waits_for_a_guard_to_pass_the_bot_waits_a_prop_in_hand_or_not() {
        let p = Perception { hold: true, ..Default::default() };
        assert_eq!(named(&p), ("wait_if_way_timed", Plan::Wait));
        let long = Perception { hidden_here: true, waited_s: LURE_AFTER_S + 0.1, lure: Some(PROP), ..p.clone() };
        assert_eq!(named(&long), ("lure_if_blocked", Plan::Throw(PROP.0, PROP.1)), "a long wait hidden: a lure first");
    }

    #[test]
    fn at_the_goal_the_bot_leaves_a_spot_a_guard_will_see_before_breaking_or_waiting_there() {
        let p = Perception { way: Some(Gait::Crouch), ..at_case() };
        assert_eq!(named(&p), ("leave_goal_if_watched", Plan::Go(Gait::Crouch)));
        let bench = Perception { at_goal: true, way: Some(Gait::Walk), ..Default::default() };
        assert_eq!(named(&bench), ("leave_goal_if_watched", Plan::Go(Gait::Walk)));
        let item = Perception { way: Some(Gait::Walk), ..in_reach_of_an_item() };
        assert_eq!(named(&item), ("act_if_in_reach", Plan::Act(ViveMsg::PickUp(ItemId(4)))), "a quiet grab first");
    }

    fn in_reach_of_an_item() -> Perception {
        Perception { at_goal: true, action: Some(ViveMsg::PickUp(ItemId(4))), ..Default::default() }
    }

    #[test]
    fn with_neither_the_way_nor_here_safe_the_bot_looks_for_a_hiding_place() {
        assert_eq!(named(&Perception::default()), ("hide_otherwise", Plan::Hide));
    }
}
