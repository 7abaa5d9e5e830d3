//! The Vive bot: plans timed ways through the museum that keep out of guards' sight (where to step and
//! when to wait: `crate::spacetime`), breaks cases, carries copies to the workbench and throws a prop
//! to lure a guard that blocks the way.
//!
//! Each frame: what it sees (the replicated state: [`Sight`]) and remembers ([`memory`]) becomes a
//! [`View`]; an ordered table of choices picks the goal ([`goal`]); the [`decide::Perception`] of
//! the moment ([`act::perceive`]) goes through the ordered decision table ([`decide`]); the plan is
//! carried out as a movement and maybe an action ([`act::carry_out`]). The museum it knows
//! ([`map`]) is built once and kept apart from its memory. It plans only with what a player could
//! know: the published patrol routes and guard numbers (`heist_shared::rules`), where each guard on
//! duty starts, and what it saw and heard since.

use bevy::prelude::*;
use glam::Vec2;
use heist_client::Inbox;
use heist_shared::protocol::{
    CaseView, ClientMsg, Gait, GameEvent, GuardView, ItemView, LobbyMsg, Phase, SessionView, ViveAvatar, ViveMsg,
};

use crate::forecast::{Forecast, Heard, Known};

/// Seconds the bot remembers a noise it made (a guard investigating within them came to look at it).
const NOISE_MEMORY_S: f32 = 15.0;

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

mod act;
mod decide;
mod goal;
mod map;
mod memory;
mod view;

use view::View;

/// The Vive bot: what it knows of the museum (built once) apart from what it remembers.
#[derive(Resource, Default)]
pub struct ViveBrain {
    style: ViveStyle,
    round: u32,
    ready_sent: bool,
    seq: u32,
    map: Option<map::Map>,
    memory: memory::Memory,
    /// Game events read so far (of [`Sight::events_received`]).
    events_read: u32,
    /// Seconds spent under each decision (by index in the decision table) and carrying something.
    spent: (Vec<f32>, f32),
    /// Actions taken, for tests and logs.
    pub actions: Vec<String>,
    /// This frame's goal and decision (by index in the decision table), for [`ViveBrain::doing`].
    last: Option<(goal::Goal, usize)>,
}

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
    /// The game events received lately, oldest first (a client may take them away each frame; the
    /// newest are at the end).
    pub events: &'a [GameEvent],
    /// How many game events have been received in all (counts the ones taken away too).
    pub events_received: u32,
}

impl ViveBrain {
    /// A fresh brain playing `style`.
    pub fn new(style: ViveStyle) -> Self {
        Self { style, ..Default::default() }
    }

    /// Seconds spent under each of the bot's decisions this round (those used), most first, and seconds
    /// spent carrying something: where a heist's time went.
    pub fn time_spent(&self) -> (Vec<(&'static str, f32)>, f32) {
        let mut by: Vec<(&'static str, f32)> = (self.spent.0.iter().enumerate())
            .filter(|(_, s)| **s > 0.0)
            .map(|(i, s)| (decide::DECISIONS[i].0, *s))
            .collect();
        by.sort_by(|a, b| b.1.total_cmp(&a.1));
        (by, self.spent.1)
    }

    /// What the bot went for and how it decided to get there in its last frame of the heist, as
    /// "break the case at (12.0, 11.5) for item 7" and "wait_if_at_goal" (the demo's `HEIST_TRACE` log).
    pub fn doing(&self) -> Option<(String, &'static str)> {
        let (goal, decision) = self.last.as_ref()?;
        Some((goal.to_string(), decide::DECISIONS[*decision].0))
    }

    /// Thinks for one frame of `dt` seconds: what to say, where to go, what to do. The bot plugin sends
    /// the result as messages; the Vive client turns it into the same intents a player's input makes.
    pub fn think(&mut self, sight: &Sight<'_>, dt: f32) -> Turn {
        let mut turn = Turn::default();
        let (session, me) = (sight.session, sight.me);
        if self.map.is_none()
            && let Some(level) = sight.level
        {
            self.map = Some(map::Map::new(level));
        }
        if session.phase == Phase::Lobby && !self.ready_sent && sight.joined {
            turn.ready = true;
            self.ready_sent = true;
        }
        let Some(map) = self.map.as_ref() else { return turn };
        if session.phase != Phase::Heist || self.style == ViveStyle::Idle {
            return turn;
        }
        let memory = &mut self.memory;
        let fresh = sight.events_received.saturating_sub(self.events_read) as usize;
        self.events_read = sight.events_received;
        for event in &sight.events[sight.events.len().saturating_sub(fresh)..] {
            if let GameEvent::Radio { about, at, answering, .. } = event {
                memory.heard_radio(&map.nav, *about, *at, answering);
            }
        }
        let tuning = map.tuning(session);
        if memory.clock_s == 0.0 {
            memory.brief(&map.level, &tuning);
        }
        memory.see(&sight.guards);
        let routes = map.patrols(session, &sight.cases, &sight.items);
        let known = Known { tuning: &tuning, nav: &map.nav, routes: &routes, alarm: session.alarm };
        let imagined = memory.imagined(&sight.guards, &known);
        let view = View {
            me,
            alarm: session.alarm,
            tuning,
            guards: sight.guards.iter().copied().chain(imagined.iter()).collect(),
            cases: sight.cases.clone(),
            items: sight.items.clone(),
            secured: session.targets.iter().filter(|t| t.1).map(|t| t.0).collect(),
        };
        memory.clock_s += dt;
        let now = memory.clock_s;
        memory.avoid.retain(|(_, until)| *until > now);
        let goal = goal::choose(&goal::Wants::new(&view, memory, map.workbench));
        memory.committed = goal.item();
        memory.noises.retain(|n| now - n.when_s < NOISE_MEMORY_S);
        let heard = Heard { noises: &memory.noises, searches: &memory.searches };
        let forecast = Forecast::new(&known, &view.guards, me.position, &heard);
        let perception = act::perceive(map, memory, &view, &forecast, &goal, self.style == ViveStyle::Reckless);
        let (decision, plan) = decide::decide(&perception);
        self.last = Some((goal.clone(), decision));
        let waiting_at_case = perception.at_goal
            && matches!(perception.action, Some(ViveMsg::Break(_)))
            && matches!(plan, decide::Plan::Wait | decide::Plan::Throw(..));
        memory.break_waited_s = if waiting_at_case { memory.break_waited_s + dt } else { 0.0 };
        if self.spent.0.len() != decide::DECISIONS.len() {
            self.spent.0 = vec![0.0; decide::DECISIONS.len()];
        }
        self.spent.0[decision] += dt;
        if !me.carrying.is_empty() {
            self.spent.1 += dt;
        }
        let (direction, gait, action) = act::carry_out(plan, map, memory, &view, &forecast);
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
            events: &self.inbox.events,
            events_received: self.inbox.received.events,
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
