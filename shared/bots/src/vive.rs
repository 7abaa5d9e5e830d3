//! The Vive bot: plans routes over the room graph, keeps out of guards' sight, breaks cases, carries
//! copies to the workbench and throws a prop to lure a guard that blocks the way.

use bevy::prelude::*;
use glam::Vec2;
use heist_client::Inbox;
use heist_shared::level::{NavGraph, WallSet};
use heist_shared::protocol::{
    CaseView, ClientMsg, Gait, GuardAlert, GuardView, ItemId, ItemKind, ItemPlace, ItemView, LobbyMsg, Phase,
    SessionView, ViveAvatar, ViveMsg,
};
use heist_shared::rules;

use crate::forecast::Forecast;

/// How the Vive bot plays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ViveStyle {
    /// Sneaks: avoids sight, waits, lures guards away.
    #[default]
    Careful,
    /// Runs straight for the copies, ignoring guards (gets caught).
    Reckless,
    /// Readies up, then stands still at the spawn (lets the timer run out).
    Idle,
}

/// Seconds the bot waits for a guard to move before throwing something to lure it away.
const LURE_AFTER_S: f32 = 4.0;
/// Seconds of waiting on one goal after which the bot tries another item.
const GIVE_UP_AFTER_S: f32 = 25.0;
/// How far ahead the bot checks that its way stays out of sight, seconds.
const LOOK_AHEAD_S: f32 = 6.0;
/// Seconds the bot waits for guards to leave earshot before breaking a case anyway.
const BREAK_PATIENCE_S: f32 = 12.0;

/// The Vive bot's memory.
#[derive(Resource, Default)]
pub struct ViveBrain {
    style: ViveStyle,
    round: u32,
    ready_sent: bool,
    seq: u32,
    map: Option<(NavGraph, WallSet, Vec2)>,
    route: Vec<Vec2>,
    route_goal: Option<Vec2>,
    waited_s: f32,
    refuge: Option<Vec2>,
    committed: Option<ItemId>,
    stuck_s: f32,
    avoid: Vec<(ItemId, f32)>,
    clock_s: f32,
    break_wait_s: f32,
    trail: Vec<Vec2>,
    level: Option<heist_shared::level::Level>,
    /// When the refuge was last chosen.
    refuge_at: f32,
    /// Each guard as last seen and when (the server sends only guards Vive could perceive): one out of
    /// sight is imagined where it has likely walked since.
    remembered: Vec<(GuardView, f32)>,
    /// Actions taken, for tests and logs.
    pub actions: Vec<String>,
}

/// Seconds an alerted guard out of sight is imagined where it was last seen; after that it is
/// imagined back on its patrol.
const ALERT_MEMORY_S: f32 = 8.0;

/// Plays Vive with a given style.
pub struct ViveBotPlugin {
    /// Play style.
    pub style: ViveStyle,
}

impl Plugin for ViveBotPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ViveBrain::new(self.style))
            .add_systems(Update, (play, crate::rounds::ask_for_another_round));
    }
}

/// Everything the bot sees this frame.
struct View<'a> {
    me: &'a ViveAvatar,
    alarm: u8,
    guards: Vec<&'a GuardView>,
    cases: Vec<&'a CaseView>,
    items: Vec<&'a ItemView>,
    secured: Vec<heist_shared::artifact::ArtifactKind>,
}

#[derive(Debug)]
enum Goal {
    /// Walk towards a point, then do nothing.
    Go(Vec2),
    /// Break this case once in reach (to get at the item).
    Break(Vec2, heist_shared::protocol::CaseId, ItemId),
    /// Pick this item up once in reach.
    Take(Vec2, ItemId),
    /// Put this copy on the workbench once in reach.
    Deliver(Vec2, ItemId),
    /// Nothing to do.
    Rest,
}

/// What the bot decided in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Turn {
    /// Say "ready" in the lobby now.
    pub ready: bool,
    /// Where to go: direction (|d| ≤ 1, museum floor), gait and facing (radians); `None` outside the heist.
    pub movement: Option<(Vec2, Gait, f32)>,
    /// What to do besides moving (break, pick up, throw, place…).
    pub action: Option<ViveMsg>,
}

/// Everything the bot may look at in one frame (the replicated state, or a client's predicted view of it).
pub struct Sight<'a> {
    /// The level, once the server has sent it.
    pub level: Option<&'a heist_shared::level::Level>,
    /// Whether the server has granted the role.
    pub joined: bool,
    /// The session.
    pub session: &'a SessionView,
    /// Vive as the bot should see itself.
    pub me: &'a ViveAvatar,
    /// The guards.
    pub guards: Vec<&'a GuardView>,
    /// The display cases.
    pub cases: Vec<&'a CaseView>,
    /// The items.
    pub items: Vec<&'a ItemView>,
}

impl ViveBrain {
    /// A fresh brain playing `style`.
    pub fn new(style: ViveStyle) -> Self {
        Self { style, ..Default::default() }
    }

    /// Thinks for one frame of `dt` seconds: what to say, where to go, what to do. The bot plugin sends
    /// the result as messages; the Vive client turns it into the same intents a player's input makes.
    pub fn think(&mut self, sight: &Sight<'_>, dt: f32) -> Turn {
        let mut turn = Turn::default();
        let (session, me) = (sight.session, sight.me);
        if self.map.is_none()
            && let Some(level) = sight.level
        {
            self.map = Some((NavGraph::new(level), WallSet::new(level), level.workbench));
            self.level = Some(level.clone());
        }
        if session.phase == Phase::Lobby && !self.ready_sent && sight.joined {
            turn.ready = true;
            self.ready_sent = true;
        }
        if session.phase != Phase::Heist || self.style == ViveStyle::Idle || self.map.is_none() {
            return turn;
        }
        // Guards out of perception are imagined where they have likely walked since.
        let now = self.clock_s;
        for g in &sight.guards {
            self.remembered.retain(|(r, _)| r.id != g.id);
            self.remembered.push(((*g).clone(), now));
        }
        let imagined: Vec<GuardView> = match &self.level {
            Some(level) => self
                .remembered
                .iter()
                .filter(|(r, _)| !sight.guards.iter().any(|g| g.id == r.id))
                .map(|(r, at)| crate::forecast::Forecast::imagine(level, r, session.alarm, now - at, ALERT_MEMORY_S))
                .collect(),
            None => Vec::new(),
        };
        let view = View {
            me,
            alarm: session.alarm,
            guards: sight.guards.iter().copied().chain(imagined.iter()).collect(),
            cases: sight.cases.clone(),
            items: sight.items.clone(),
            secured: session.targets.iter().filter(|t| t.1).map(|t| t.0).collect(),
        };
        self.clock_s += dt;
        let now = self.clock_s;
        self.avoid.retain(|(_, until)| *until > now);
        let goal = choose_goal(self, &view);
        self.committed = match &goal {
            Goal::Break(_, _, item) | Goal::Take(_, item) => Some(*item),
            _ => None,
        };
        let (direction, gait, action) = steer(self, &view, goal, dt);
        // Waiting on one goal for too long: try another item for a while.
        if direction == Vec2::ZERO && action.is_none() {
            self.stuck_s += dt;
            if self.stuck_s > GIVE_UP_AFTER_S
                && let Some(item) = self.committed.take()
            {
                self.avoid.push((item, now + 60.0));
                self.stuck_s = 0.0;
            }
        } else {
            self.stuck_s = 0.0;
        }
        if let Some(action) = &action {
            self.actions.push(format!("{action:?}"));
        }
        let facing = if direction.length_squared() > 0.0 { direction.y.atan2(direction.x) } else { me.facing };
        turn.movement = Some((direction, gait, facing));
        turn.action = action;
        turn
    }
}

/// The replicated state a Vive bot looks at, as one system parameter: the bot plugin and the Vive
/// client (which shows the brain its predicted body) both read the world through it.
#[derive(bevy::ecs::system::SystemParam)]
pub struct Seen<'w, 's> {
    inbox: Res<'w, Inbox>,
    session: Query<'w, 's, &'static SessionView>,
    avatar: Query<'w, 's, &'static ViveAvatar>,
    guards: Query<'w, 's, &'static GuardView>,
    cases: Query<'w, 's, &'static CaseView>,
    items: Query<'w, 's, &'static ItemView>,
}

impl Seen<'_, '_> {
    /// The replicated avatar, once there is one.
    pub fn avatar(&self) -> Option<&ViveAvatar> {
        self.avatar.single().ok()
    }

    /// What the bot sees, with itself as `me` (the replicated avatar, or a client's prediction of it);
    /// `None` before the session and the avatar are replicated.
    pub fn sight<'a>(&'a self, me: &'a ViveAvatar) -> Option<Sight<'a>> {
        Some(Sight {
            level: self.inbox.level.as_ref(),
            joined: self.inbox.role.is_some(),
            session: self.session.single().ok()?,
            me,
            guards: self.guards.iter().collect(),
            cases: self.cases.iter().collect(),
            items: self.items.iter().collect(),
        })
    }
}

fn play(
    mut brain: ResMut<ViveBrain>,
    time: Res<Time>,
    seen: Seen,
    inbox: Res<heist_client::Inbox>,
    mut out: MessageWriter<ClientMsg>,
) {
    let round = inbox.current_round();
    if brain.round != round {
        // A new round: plans of the last one go; the move numbers carry on, as the server's do.
        let first = brain.round == 0;
        *brain = ViveBrain { round, seq: brain.seq, ready_sent: !first, ..ViveBrain::new(brain.style) };
    }
    let Some(sight) = seen.avatar().and_then(|me| seen.sight(me)) else { return };
    let turn = brain.think(&sight, time.delta_secs());
    if turn.ready {
        out.write(ClientMsg::Lobby(LobbyMsg::Ready));
    }
    if let Some(action) = turn.action {
        out.write(ClientMsg::Vive(action));
    }
    if let Some((direction, gait, facing)) = turn.movement {
        brain.seq += 1;
        out.write(ClientMsg::Vive(ViveMsg::Move { seq: brain.seq, direction, gait, facing }));
    }
}

fn is_copy(view: &View<'_>, id: ItemId) -> bool {
    view.items.iter().any(|i| i.id == id && matches!(i.kind, ItemKind::Copy { .. }))
}

fn choose_goal(brain: &ViveBrain, view: &View<'_>) -> Goal {
    let Some((_, _, workbench)) = &brain.map else { return Goal::Rest };
    let me = view.me.position;
    let carried_copy = view.me.carrying.iter().copied().find(|&i| is_copy(view, i));
    let hands_full = view.me.carrying.len() >= rules::CARRY_LIMIT;

    // Copies still worth fetching: their artifact is not secured yet.
    let wanted = view.items.iter().filter(|i| match &i.kind {
        ItemKind::Copy { artifact, .. } => {
            !view.secured.contains(artifact) && !brain.avoid.iter().any(|(a, _)| *a == i.id)
        }
        ItemKind::Prop => false,
    });
    let fetchable: Vec<(Vec2, &ItemView)> = wanted
        .filter_map(|i| match i.place {
            ItemPlace::Floor(p) => Some((p, *i)),
            ItemPlace::InCase(c) => view.cases.iter().find(|cv| cv.id == c).map(|cv| (cv.position, *i)),
            _ => None,
        })
        .collect();
    let nearest = fetchable.iter().min_by(|a, b| me.distance(a.0).total_cmp(&me.distance(b.0)));

    // Stick to the item we were going for while it is still there, so the bot never dithers
    // between two goals of nearly equal appeal.
    if !hands_full
        && let Some(item) = brain.committed
        && !brain.avoid.iter().any(|(a, _)| *a == item)
        && let Some(view_item) = view.items.iter().find(|i| i.id == item)
    {
        let at = match view_item.place {
            ItemPlace::Floor(p) => Some(p),
            ItemPlace::InCase(c) => view.cases.iter().find(|cv| cv.id == c).map(|cv| cv.position),
            _ => None,
        };
        let still_wanted = match &view_item.kind {
            ItemKind::Copy { artifact, .. } => !view.secured.contains(artifact),
            ItemKind::Prop => true,
        };
        if let Some(at) = at
            && still_wanted
        {
            return goal_for(view, at, view_item);
        }
    }
    if let Some(copy) = carried_copy {
        // A second copy close by is worth the detour when hands allow.
        if !hands_full
            && let Some((p, item)) = nearest
            && me.distance(*p) < 6.0
        {
            return goal_for(view, *p, item);
        }
        return Goal::Deliver(*workbench, copy);
    }
    let carrying_prop = view.me.carrying.iter().any(|&i| !is_copy(view, i));
    if !carrying_prop
        && !hands_full
        && let Some((p, prop)) = view
            .items
            .iter()
            .filter(|i| matches!(i.kind, ItemKind::Prop))
            .filter_map(|i| match i.place {
                ItemPlace::Floor(p) => Some((p, *i)),
                _ => None,
            })
            .min_by(|a, b| me.distance(a.0).total_cmp(&me.distance(b.0)))
        && me.distance(p) < 5.0
    {
        return Goal::Take(p, prop.id); // something to throw when a guard blocks the way
    }
    match nearest {
        Some((p, item)) => goal_for(view, *p, item),
        None => Goal::Go(*workbench),
    }
}

fn goal_for(view: &View<'_>, at: Vec2, item: &ItemView) -> Goal {
    match item.place {
        ItemPlace::InCase(c) if view.cases.iter().any(|cv| cv.id == c && !cv.broken) => Goal::Break(at, c, item.id),
        _ => Goal::Take(at, item.id),
    }
}

/// Turns a goal into a movement and maybe an action, keeping out of sight.
fn steer(brain: &mut ViveBrain, view: &View<'_>, goal: Goal, dt: f32) -> (Vec2, Gait, Option<ViveMsg>) {
    let me = view.me.position;
    let (target, in_reach_action) = match goal {
        Goal::Rest => return (Vec2::ZERO, Gait::Crouch, None),
        Goal::Go(p) => (p, None),
        Goal::Break(p, c, _) => (p, Some(ViveMsg::Break(c))),
        Goal::Take(p, i) => (p, Some(ViveMsg::PickUp(i))),
        Goal::Deliver(p, i) => {
            let busy = view.items.iter().any(|it| it.place == ItemPlace::Workbench);
            (p, (!busy).then_some(ViveMsg::PlaceOnWorkbench(i)))
        }
    };
    let reckless = brain.style == ViveStyle::Reckless;
    let Some((nav, walls, home)) = brain.map.clone() else { return (Vec2::ZERO, Gait::Walk, None) };

    // Chased: run for the place we reach furthest ahead of every guard, and hope it loses sight.
    if !reckless && view.guards.iter().any(|g| g.alert == GuardAlert::Chasing) {
        return (flee(brain, view, &nav, me, home), Gait::Run, None);
    }
    let Some(level) = brain.level.clone() else { return (Vec2::ZERO, Gait::Crouch, None) };
    let forecast = Forecast::new(&level, &view.guards, view.alarm, me);
    // Too close for comfort, seen or not (walls and doors are thin): treat as exposed.
    let crowded = view.guards.iter().any(|g| g.position.distance(me) < 3.0);
    let exposed = !reckless && (crowded || forecast.seen(me, 0.0, true, &walls));

    if me.distance(target) <= rules::REACH * 0.8 {
        let Some(action) = in_reach_action else { return (Vec2::ZERO, Gait::Crouch, None) };
        if exposed {
            return hide(brain, view, &forecast, &nav, &walls, me);
        }
        if let ViveMsg::Break(_) = action
            && !reckless
            && !safe_to_break(&nav, view, target)
        {
            brain.break_wait_s += dt;
            if brain.break_wait_s < BREAK_PATIENCE_S {
                return (Vec2::ZERO, Gait::Crouch, None);
            }
        }
        brain.break_wait_s = 0.0;
        return (Vec2::ZERO, Gait::Walk, Some(action));
    }

    if brain.route_goal.is_none_or(|g| g.distance(target) > 0.3) || brain.route.is_empty() {
        let guard_rooms: Vec<usize> = view.guards.iter().filter_map(|g| nav.room_at(g.position)).collect();
        let cost = |room: usize| 1.0 + 3.0 * guard_rooms.iter().filter(|&&r| r == room).count() as f32;
        brain.route = if reckless { nav.route(me, target) } else { nav.route_avoiding(me, target, cost) }
            .unwrap_or_else(|| vec![target]);
        brain.route.reverse();
        brain.route_goal = Some(target);
    }
    while brain.route.len() > 1 && brain.route.last().is_some_and(|w| w.distance(me) < 0.25) {
        brain.route.pop();
    }
    let Some(&waypoint) = brain.route.last() else { return (Vec2::ZERO, Gait::Walk, None) };
    let direction = (waypoint - me).normalize_or_zero();
    if reckless {
        return (direction, Gait::Run, None);
    }

    brain.trail.push(me);
    if brain.trail.len() > 900 {
        brain.trail.remove(0);
    }
    // Walk on only if the next seconds of the route stay out of every guard's forecast view.
    let path: Vec<Vec2> = brain.route.iter().rev().copied().collect();
    let quiet = view.guards.iter().all(|g| nav.heard_margin(me, g.position, rules::RUN_LOUDNESS * 1.5) < 0.0);
    if quiet && forecast.path_hidden(me, &path, rules::RUN_SPEED, LOOK_AHEAD_S, false, &walls) {
        brain.waited_s = 0.0;
        brain.refuge = None;
        return (direction, Gait::Run, None);
    }
    if forecast.path_hidden(me, &path, rules::WALK_SPEED, LOOK_AHEAD_S, false, &walls) {
        brain.waited_s = 0.0;
        brain.refuge = None;
        return (direction, Gait::Walk, None);
    }
    if forecast.path_hidden(me, &path, rules::CROUCH_SPEED, LOOK_AHEAD_S * 0.5, true, &walls) {
        brain.waited_s = 0.0;
        return (direction, Gait::Crouch, None);
    }
    // The way is watched: wait where we are if it stays hidden, otherwise find a better hiding place.
    brain.waited_s += dt;
    if !exposed && forecast.hidden_for(me, LOOK_AHEAD_S * 0.5, &walls) {
        return lure_or_wait(brain, view, me, &walls);
    }
    hide(brain, view, &forecast, &nav, &walls, me)
}

/// Moves to the nearest spot we can reach unseen that then stays hidden; failing that, away from the
/// nearest guard.
fn hide(
    brain: &mut ViveBrain,
    view: &View<'_>,
    forecast: &Forecast,
    nav: &NavGraph,
    walls: &WallSet,
    me: Vec2,
) -> (Vec2, Gait, Option<ViveMsg>) {
    brain.route_goal = None;
    let mut candidates: Vec<Vec2> = brain.trail.iter().rev().step_by(15).take(20).copied().collect();
    candidates.extend(nav.room_centres());
    for dx in [-3.0f32, 0.0, 3.0] {
        for dy in [-3.0f32, 0.0, 3.0] {
            candidates.push(me + Vec2::new(dx, dy));
        }
    }
    let best = candidates
        .into_iter()
        .filter(|c| nav.room_at(*c).is_some())
        .filter_map(|c| {
            let route = nav.route(me, c)?;
            let length = nav.route_length(me, c);
            let ok =
                forecast.path_hidden(me, &route, rules::WALK_SPEED, length / rules::WALK_SPEED + 3.0, false, walls);
            ok.then_some((length, route))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((_, route)) = best
        && let Some(first) = route.into_iter().find(|p| p.distance(me) > 0.2)
    {
        return ((first - me).normalize_or_zero(), Gait::Walk, None);
    }
    let home = brain.map.as_ref().map_or(me, |m| m.2);
    (flee(brain, view, nav, me, home), Gait::Walk, None)
}

/// Direction towards the refuge chosen by [`pick_refuge`] (the workbench when there is none); the
/// choice is reconsidered every second and dropped once reached.
fn flee(brain: &mut ViveBrain, view: &View<'_>, nav: &NavGraph, me: Vec2, home: Vec2) -> Vec2 {
    if brain.refuge.is_some_and(|r| r.distance(me) < 1.5) {
        brain.refuge = None; // reached it and still in danger: pick the next one
    }
    // Think again every second (guards move), but switch only for a clearly better refuge.
    if brain.refuge.is_none() || brain.clock_s - brain.refuge_at > 1.0 {
        brain.refuge_at = brain.clock_s;
        brain.refuge = pick_refuge(brain, view, nav, me, brain.refuge);
    }
    let refuge = brain.refuge.unwrap_or(home);
    let first = nav.route(me, refuge).and_then(|r| r.into_iter().find(|p| p.distance(me) > 0.3)).unwrap_or(refuge);
    brain.route_goal = None;
    (first - me).normalize_or_zero()
}

/// The spot (a room centre or the middle of a room quarter) we keep the most room at along the whole
/// way there: ahead of every alerted guard, and outside every patrolling guard's sight.
fn pick_refuge(brain: &ViveBrain, view: &View<'_>, nav: &NavGraph, me: Vec2, current: Option<Vec2>) -> Option<Vec2> {
    let level = brain.level.as_ref()?;
    let spots = level.rooms.iter().flat_map(|r| {
        let (c, h) = ((r.min + r.max) * 0.5, (r.max - r.min) * 0.25);
        [c, c + h, c - h, c + Vec2::new(h.x, -h.y), c + Vec2::new(-h.x, h.y)]
    });
    let room_left = |p: Vec2| {
        let Some(route) = nav.route(me, p) else { return f32::NEG_INFINITY };
        let (mut last, mut mine, mut worst) = (me, 0.0f32, 20.0f32);
        for wp in points_along(me, &route) {
            mine += last.distance(wp);
            last = wp;
            for g in &view.guards {
                let theirs = nav.route_length(g.position, wp);
                worst = worst.min(match g.alert {
                    GuardAlert::Patrolling | GuardAlert::Returning => theirs - 6.0,
                    _ => theirs - mine,
                });
            }
        }
        worst + 0.05 * mine
    };
    let best = spots.filter(|p| p.distance(me) > 6.0).map(|p| (room_left(p), p)).max_by(|a, b| a.0.total_cmp(&b.0));
    match (current, best) {
        (Some(c), Some((s, _))) if room_left(c) + 3.0 >= s => Some(c),
        (_, best) => best.map(|b| b.1),
    }
}

/// Points every metre along a polyline starting at `from`.
fn points_along(from: Vec2, route: &[Vec2]) -> Vec<Vec2> {
    let mut at = from;
    let mut points = Vec::new();
    for &wp in route {
        let steps = at.distance(wp).ceil().max(1.0) as usize;
        points.extend((1..=steps).map(|k| at.lerp(wp, k as f32 / steps as f32)));
        at = wp;
    }
    points
}

/// Waits crouching; after a while, throws a carried prop past the nearest guard to draw it away.
fn lure_or_wait(brain: &mut ViveBrain, view: &View<'_>, me: Vec2, _walls: &WallSet) -> (Vec2, Gait, Option<ViveMsg>) {
    let nearest = view.guards.iter().min_by(|a, b| a.position.distance(me).total_cmp(&b.position.distance(me)));
    if brain.waited_s > LURE_AFTER_S
        && let Some(g) = nearest
        && let Some(&prop) = view.me.carrying.iter().find(|&&i| !is_copy(view, i))
    {
        brain.waited_s = 0.0;
        let beyond = g.position + (g.position - me).normalize_or_zero() * 7.0;
        return (Vec2::ZERO, Gait::Crouch, Some(ViveMsg::Throw { item: prop, target: beyond }));
    }
    (Vec2::ZERO, Gait::Crouch, None)
}

fn safe_to_break(nav: &NavGraph, view: &View<'_>, at: Vec2) -> bool {
    let hearing = 1.0 + 0.25 * f32::from(view.alarm);
    view.guards.iter().all(|g| nav.heard_margin(at, g.position, rules::GLASS_LOUDNESS * hearing) < -2.0)
}
