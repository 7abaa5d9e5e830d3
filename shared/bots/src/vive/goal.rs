//! What the Vive bot is going for, as small named choices tried in order (the first that applies
//! wins), over [`Wants`]: what it carries, the item it committed to, the nearest copies and props.

use glam::Vec2;
use heist_shared::protocol::{CaseId, GuardAlert, ItemId, ItemKind, ItemPlace, ItemView};
use heist_shared::rules;

use super::memory::Memory;
use super::view::View;

/// A second copy this close is worth the detour before delivering, metres.
const SECOND_COPY_DETOUR_M: f32 = 6.0;
/// A prop this close is picked up (to throw when a guard blocks the way), metres.
const PROP_DETOUR_M: f32 = 5.0;

/// Where the bot goes and what it does there.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Goal {
    /// Walk towards a point, then do nothing.
    Go(Vec2),
    /// Break this case once in reach (to get at the item).
    Break(Vec2, CaseId, ItemId),
    /// Pick this item up once in reach.
    Take(Vec2, ItemId),
    /// Put this copy on the workbench once in reach.
    Deliver(Vec2, ItemId),
}

impl Goal {
    /// Where it is.
    pub fn at(&self) -> Vec2 {
        match *self {
            Goal::Go(p) | Goal::Break(p, ..) | Goal::Take(p, _) | Goal::Deliver(p, _) => p,
        }
    }

    /// The item fetched, for breaking or taking.
    pub fn item(&self) -> Option<ItemId> {
        match *self {
            Goal::Break(_, _, i) | Goal::Take(_, i) => Some(i),
            _ => None,
        }
    }
}

impl std::fmt::Display for Goal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Goal::Go(p) => write!(f, "go to ({:.1}, {:.1})", p.x, p.y),
            Goal::Break(p, _, item) => write!(f, "break the case at ({:.1}, {:.1}) for item {}", p.x, p.y, item.0),
            Goal::Take(p, item) => write!(f, "take item {} at ({:.1}, {:.1})", item.0, p.x, p.y),
            Goal::Deliver(p, item) => write!(f, "bring item {} to the workbench at ({:.1}, {:.1})", item.0, p.x, p.y),
        }
    }
}

/// What goal choice looks at.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Wants {
    pub workbench: Vec2,
    pub hands_full: bool,
    /// A copy in hand.
    pub carried_copy: Option<ItemId>,
    pub carrying_prop: bool,
    /// The goal for the item committed to, while it is still wanted and not given up on.
    pub committed: Option<Goal>,
    /// The nearest copy still worth fetching: (distance, goal).
    pub nearest_copy: Option<(f32, Goal)>,
    /// The nearest prop on the floor: (distance, goal).
    pub nearest_prop: Option<(f32, Goal)>,
    /// Some guard in view is not on his round (alerted, searching, coming to check a noise).
    pub guards_stirred: bool,
}

/// Stick to the item we were going for while it is still wanted, so the bot never dithers between two
/// goals of nearly equal appeal (or between a copy and the bench).
fn keep_committed_if_still_wanted(w: &Wants) -> Option<Goal> {
    if w.hands_full { None } else { w.committed.clone() }
}

/// With a copy in hand, fetch a second one close by before walking to the bench, unless the guards
/// are stirred (someone is coming to look: the copy in hand goes to safety first).
fn fetch_second_copy_if_close(w: &Wants) -> Option<Goal> {
    let (d, goal) = w.nearest_copy.as_ref()?;
    (w.carried_copy.is_some() && !w.hands_full && !w.guards_stirred && *d < SECOND_COPY_DETOUR_M).then(|| goal.clone())
}

/// Bring a copy in hand to the workbench.
fn deliver_if_carrying_copy(w: &Wants) -> Option<Goal> {
    w.carried_copy.map(|copy| Goal::Deliver(w.workbench, copy))
}

/// Pick up a prop close by: something to throw when a guard blocks the way.
fn take_prop_if_close(w: &Wants) -> Option<Goal> {
    let (d, goal) = w.nearest_prop.as_ref()?;
    (!w.carrying_prop && !w.hands_full && *d < PROP_DETOUR_M).then(|| goal.clone())
}

/// Go for the nearest copy still worth fetching.
fn fetch_nearest_copy(w: &Wants) -> Option<Goal> {
    w.nearest_copy.as_ref().map(|(_, g)| g.clone())
}

/// Nothing left to fetch (or all given up on for now): wait by the workbench.
fn wait_at_workbench_otherwise(w: &Wants) -> Option<Goal> {
    Some(Goal::Go(w.workbench))
}

/// The choices in priority order.
const CHOICES: &[fn(&Wants) -> Option<Goal>] = &[
    keep_committed_if_still_wanted,
    fetch_second_copy_if_close,
    deliver_if_carrying_copy,
    take_prop_if_close,
    fetch_nearest_copy,
    wait_at_workbench_otherwise,
];

/// The first choice that applies.
pub(crate) fn choose(w: &Wants) -> Goal {
    CHOICES.iter().find_map(|f| f(w)).unwrap_or(Goal::Go(w.workbench))
}

impl Wants {
    /// Reads what goal choice needs from the view and the memory.
    pub fn new(view: &View<'_>, memory: &Memory, workbench: Vec2) -> Self {
        let me = view.me.position;
        let is_copy = |id: ItemId| view.items.iter().any(|i| i.id == id && matches!(i.kind, ItemKind::Copy { .. }));
        let wanted = |i: &ItemView| match &i.kind {
            ItemKind::Copy { artifact, .. } => !view.secured.contains(artifact) && !memory.avoids(i.id),
            ItemKind::Prop => false,
        };
        let goal_for = |i: &ItemView| -> Option<Goal> {
            match i.place {
                ItemPlace::Floor(p) => Some(Goal::Take(p, i.id)),
                ItemPlace::InCase(c) => {
                    let case = view.cases.iter().find(|cv| cv.id == c)?;
                    Some(if case.broken {
                        Goal::Take(case.position, i.id)
                    } else {
                        Goal::Break(case.position, c, i.id)
                    })
                }
                _ => None,
            }
        };
        let nearest = |pick: &dyn Fn(&ItemView) -> bool| {
            view.items
                .iter()
                .filter(|i| pick(i))
                .filter_map(|i| goal_for(i))
                .map(|g| (me.distance(g.at()), g))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        let committed = memory
            .committed
            .and_then(|id| view.items.iter().find(|i| i.id == id))
            .filter(|i| wanted(i))
            .and_then(|i| goal_for(i));
        Self {
            workbench,
            hands_full: view.me.carrying.len() >= rules::CARRY_LIMIT,
            carried_copy: view.me.carrying.iter().copied().find(|&i| is_copy(i)),
            carrying_prop: view.me.carrying.iter().any(|&i| !is_copy(i)),
            committed,
            nearest_copy: nearest(&|i| wanted(i)),
            nearest_prop: nearest(&|i| {
                matches!(i.kind, ItemKind::Prop) && matches!(i.place, ItemPlace::Floor(_)) && !memory.avoids(i.id)
            }),
            guards_stirred: view
                .guards
                .iter()
                .any(|g| !matches!(g.alert, GuardAlert::Patrolling | GuardAlert::Returning)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_goal_reads_as_what_the_bot_goes_for() {
        let at = Vec2::new(12.0, 11.5);
        assert_eq!(Goal::Break(at, CaseId(8), ItemId(7)).to_string(), "break the case at (12.0, 11.5) for item 7");
        assert_eq!(Goal::Take(at, ItemId(7)).to_string(), "take item 7 at (12.0, 11.5)");
        assert_eq!(
            Goal::Deliver(Vec2::new(5.0, 12.0), ItemId(7)).to_string(),
            "bring item 7 to the workbench at (5.0, 12.0)"
        );
        assert_eq!(Goal::Go(Vec2::new(5.0, 12.0)).to_string(), "go to (5.0, 12.0)");
    }

    const BENCH: Vec2 = Vec2::new(1.0, 1.0);

    fn copy_at(x: f32, id: u16) -> (f32, Goal) {
        (x, Goal::Break(Vec2::new(x, 0.0), CaseId(id), ItemId(id)))
    }

    fn wants() -> Wants {
        Wants { workbench: BENCH, ..Default::default() }
    }

    #[test]
    fn the_bot_keeps_to_the_item_it_chose_over_a_nearer_one() {
        let w = Wants { committed: Some(copy_at(9.0, 1).1), nearest_copy: Some(copy_at(3.0, 2)), ..wants() };
        assert_eq!(choose(&w), copy_at(9.0, 1).1);
        let full = Wants { hands_full: true, carried_copy: Some(ItemId(5)), ..w };
        assert_eq!(choose(&full), Goal::Deliver(BENCH, ItemId(5)), "full hands go to the bench");
    }

    #[test]
    fn with_a_copy_in_hand_a_second_close_by_is_fetched_and_a_far_one_is_not() {
        let near = Wants { carried_copy: Some(ItemId(7)), nearest_copy: Some(copy_at(4.0, 2)), ..wants() };
        assert_eq!(choose(&near), copy_at(4.0, 2).1);
        let stirred = Wants { guards_stirred: true, ..near.clone() };
        assert_eq!(choose(&stirred), Goal::Deliver(BENCH, ItemId(7)), "a guard coming: the copy in hand first");
        let chosen = Wants { committed: Some(copy_at(4.0, 2).1), ..stirred };
        assert_eq!(choose(&chosen), copy_at(4.0, 2).1, "but a second copy already chosen is not dropped");
        let far = Wants { nearest_copy: Some(copy_at(12.0, 2)), ..near };
        assert_eq!(choose(&far), Goal::Deliver(BENCH, ItemId(7)));
    }

    #[test]
    fn a_prop_close_by_is_picked_up_before_the_next_copy_but_only_one() {
        let prop = (2.0, Goal::Take(Vec2::new(2.0, 0.0), ItemId(9)));
        let w = Wants { nearest_prop: Some(prop.clone()), nearest_copy: Some(copy_at(8.0, 2)), ..wants() };
        assert_eq!(choose(&w), prop.1);
        let holding = Wants { carrying_prop: true, ..w };
        assert_eq!(choose(&holding), copy_at(8.0, 2).1);
    }

    #[test]
    fn a_prop_given_up_on_is_not_wanted_again_until_its_time_is_up() {
        // A thrown prop that lands on a guard's beat used to be chosen again frame after frame (seed 4
        // on normal: 200 s spent edging round Clara for it).
        let me = heist_shared::protocol::ViveAvatar { position: Vec2::new(15.0, 19.0), ..Default::default() };
        let prop = ItemView { id: ItemId(9), kind: ItemKind::Prop, place: ItemPlace::Floor(Vec2::new(17.0, 19.0)) };
        let view = View {
            me: &me,
            alarm: 0,
            tuning: rules::GuardTuning::default(),
            guards: Vec::new(),
            cases: Vec::new(),
            items: vec![&prop],
            secured: Vec::new(),
        };
        let mut memory = Memory::default();
        let wanted = |memory: &Memory| Wants::new(&view, memory, BENCH).nearest_prop.map(|(_, goal)| goal);
        assert_eq!(wanted(&memory), Some(Goal::Take(Vec2::new(17.0, 19.0), ItemId(9))));
        memory.avoid.push((ItemId(9), 60.0));
        assert_eq!(wanted(&memory), None, "given up on: left lying");
        memory.clock_s = 61.0;
        assert!(wanted(&memory).is_some(), "a minute later it is wanted again");
    }

    #[test]
    fn with_nothing_left_to_fetch_the_bot_waits_at_the_workbench() {
        assert_eq!(choose(&wants()), Goal::Go(BENCH));
    }
}
