//! The authoritative game: every rule of a heist, as plain data stepped by `dt`.
//!
//! Nothing here touches the network or the clock: [`Game::apply`] takes one client message, [`Game::step`]
//! advances time, and both leave what happened in [`Game::drain_outgoing`]. That keeps every rule
//! deterministic for a seed and testable without a server.

mod actions;
mod guard;
mod radio;
mod setup;

pub use guard::{Guard, GuardState, Perception};
pub use radio::Radio;

use glam::Vec2;
use heist_shared::artifact::{ArtifactKind, Briefing, CopyTraits, HapticMesh, Material};
use heist_shared::level::{Level, NavGraph, WallSet};
use heist_shared::protocol::{
    CaseId, ClientMsg, GameEvent, ItemId, ItemKind, ItemPlace, LobbyMsg, LossReason, NoiseKind, PhantomMsg,
    PhantomTool, Phase, Refusal, Role, ServerMsg, Stance, ViveMsg, verify,
};
use heist_shared::rules;
use rand_chacha::ChaCha8Rng;

/// Seconds a running heist waits, paused, for someone to take the seat of a player who left on purpose
/// (with the join code) before it is lost as abandoned. A dropped player's seat is kept for them longer,
/// [`rules::SEAT_HOLD_S`].
pub const ABANDON_GRACE_S: f32 = 20.0;

/// Seconds a session waits after a result for another round before it ends (unless
/// [`GameOptions::idle_end_s`] says otherwise); also how long it outlives its last player.
pub const SESSION_IDLE_S: f32 = 300.0;
/// Seconds before an idle session ends at which both players are warned.
pub const ENDING_WARNING_S: f32 = 60.0;

/// Options that change a session without editing the level.
#[derive(Clone, Debug, Default)]
pub struct GameOptions {
    /// Seed for copy traits, case assignment and guard decisions (of the first round; each later round's
    /// seed follows from it by [`next_round_seed`]).
    pub seed: u64,
    /// Replaces the level's time limit (seconds).
    pub time_limit_s: Option<f32>,
    /// Replaces [`SESSION_IDLE_S`].
    pub idle_end_s: Option<f32>,
    /// Draw each later round's seed from the operating system instead of [`next_round_seed`]: what a
    /// hosted session with a random first seed needs, since the host reads the log, where a round's seed
    /// appears when it ends, and a derived seed would tell him the next round's real copies.
    pub random_rounds: bool,
    /// A lobby nobody ever joined idles out too (a session created on a `serve`d server whose creator
    /// never came); a `host`'s own session waits for its players for as long as the process runs.
    pub ends_unjoined: bool,
    /// How hard the guards are (the level's tuning for it: [`Level::tuning`]).
    pub difficulty: rules::Difficulty,
}

/// The seed of the round after one played on `seed` (SplitMix64), when rounds are reproducible (a given
/// `--seed`, tests, the demo).
pub fn next_round_seed(seed: u64) -> u64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Who receives an outgoing message.
#[derive(Clone, Debug, PartialEq)]
pub enum Outgoing {
    /// Both players.
    All(ServerMsg),
    /// One role only.
    To(Role, ServerMsg),
}

/// Vive's server-side state.
#[derive(Clone, Debug, Default)]
pub struct Vive {
    /// Position, metres.
    pub position: Vec2,
    /// Velocity, m/s.
    pub velocity: Vec2,
    /// Facing yaw, radians.
    pub facing: f32,
    /// Stance derived from the last gait.
    pub stance: Stance,
    /// Carried items.
    pub carrying: Vec<ItemId>,
    /// Last applied input sequence number.
    pub last_input_seq: u32,
    /// Movement inputs received and not yet applied, oldest first: one moves the body for one tick.
    pub inputs: std::collections::VecDeque<MoveInput>,
    /// Ticks of movement the client may still catch up on (see [`MAX_MOVE_CREDIT`]); negative after a
    /// fast-forward for an action, repaid by later ticks.
    pub move_credit: i32,
    footstep_timer: f32,
}

/// One movement input: a tick's worth of walking.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveInput {
    /// Its sequence number.
    pub seq: u32,
    /// Direction, |d| ≤ 1.
    pub direction: Vec2,
    /// Speed, m/s.
    pub speed: f32,
    /// Stance.
    pub stance: Stance,
    /// Facing yaw, radians.
    pub facing: f32,
}

/// One server tick, seconds (what one movement input is worth).
pub const TICK_S: f32 = (1.0 / heist_shared::protocol::TICK_HZ) as f32;

/// Inputs that may wait; older ones are dropped beyond this (the client reconciles).
pub const MAX_QUEUED_INPUTS: usize = 60;
/// Ticks of movement a client can bank while its inputs are late (half a second), to catch up on later —
/// so inputs bunched by jitter or a resend are all applied and the backlog drains, but a client sending
/// faster than the tick rate gains no speed.
pub const MAX_MOVE_CREDIT: i32 = 30;
/// Inputs applied in one tick at most (catching up).
pub const MAX_INPUTS_PER_TICK: usize = 4;
/// Ticks of movement an action may fast-forward beyond the banked credit (the inputs that arrived in the
/// same frame as it); later ticks repay them.
pub const MAX_MOVE_DEBT: i32 = MAX_INPUTS_PER_TICK as i32;

/// A display case.
#[derive(Clone, Debug)]
pub struct Case {
    /// Position, metres.
    pub position: Vec2,
    /// Shattered?
    pub broken: bool,
    /// A guard found it shattered and reported it (the alarm went up once for it).
    pub reported: bool,
}

/// An item and, for copies, its hidden truth.
#[derive(Clone, Debug)]
pub struct Item {
    /// What anyone can see.
    pub kind: ItemKind,
    /// Where it is.
    pub place: ItemPlace,
    /// For copies: which target, its traits, and whether it is the real one. Never replicated.
    pub truth: Option<CopyTruth>,
}

/// What only the server knows about a copy.
#[derive(Clone, Debug)]
pub struct CopyTruth {
    /// Index of its target in `Game::targets`.
    pub target: usize,
    /// What touch can tell.
    pub traits: CopyTraits,
    /// The one real copy of its target?
    pub real: bool,
    /// Its haptic geometry (generated once at set-up).
    pub mesh: HapticMesh,
    /// Its material.
    pub material: Material,
}

/// A target artifact's progress.
#[derive(Clone, Debug)]
pub struct Target {
    /// Which artifact.
    pub kind: ArtifactKind,
    /// What Phantom is told about the real copy.
    pub briefing: Briefing,
    /// Secured yet?
    pub secured: bool,
}

/// A heist session.
#[derive(Clone, Debug)]
pub struct Game {
    /// The level being played.
    pub level: Level,
    /// Walls for collision and sight.
    pub walls: WallSet,
    /// Room graph for routes and sound.
    pub nav: NavGraph,
    /// Current phase.
    pub phase: Phase,
    /// Seconds of game time left.
    pub time_left_s: f32,
    /// Seconds of heist time elapsed.
    pub elapsed_s: f32,
    /// Alarm level.
    pub alarm: u8,
    /// Vive.
    pub vive: Vive,
    /// Guards on duty.
    pub guards: Vec<Guard>,
    /// The session's difficulty.
    pub difficulty: rules::Difficulty,
    /// What the guards can do (the level's tuning for the difficulty).
    pub tuning: rules::GuardTuning,
    /// Display cases.
    pub cases: Vec<Case>,
    /// Items (copies and props), indexed by `ItemId`.
    pub items: Vec<Item>,
    /// Targets in level order.
    pub targets: Vec<Target>,
    /// The copy on the workbench.
    pub workbench: Option<ItemId>,
    /// Connected roles (Vive, Phantom).
    pub present: (bool, bool),
    /// Where Phantom's tool was last reported (workbench frame), for Vive's client to draw.
    pub tool: PhantomTool,
    /// The seed this round was made from (secret while it runs: it decides which copy is real).
    pub seed: u64,
    /// The round being played: 1 for the first heist of the session, one more for each rematch.
    pub round: u32,
    /// Set once the session is over for good (idle after a result, or empty): the server closes it.
    pub closed: bool,
    /// Set when the server drains ([`Game::drain`]): no new round, and the session closes once no heist
    /// is under way.
    pub draining: bool,
    /// Which guard caught Vive, and where, once one has (for the sweep's causes of losses).
    pub caught_by: Option<(usize, Vec2)>,
    options: GameOptions,
    ready: (bool, bool),
    rematch: (bool, bool),
    /// Seconds each dropped player's seat has been kept for them (Vive, Phantom); `None`: not kept.
    kept: [Option<f32>; 2],
    idle_s: f32,
    warned_ending: bool,
    joined_once: bool,
    absent_s: f32,
    noises: Vec<(Vec2, f32)>,
    outgoing: Vec<Outgoing>,
    rng: ChaCha8Rng,
    radio: radio::Radio,
    /// The alarm level and hot rooms the guards' patrols were last laid out for.
    patrols_for: Option<(u8, Vec<usize>)>,
    /// Where each tick lists the hot rooms to compare with `patrols_for` (no allocation a tick).
    hot_scratch: Vec<usize>,
}

fn slot(role: Role) -> usize {
    match role {
        Role::Vive => 0,
        Role::Phantom => 1,
    }
}

fn get(pair: (bool, bool), role: Role) -> bool {
    if slot(role) == 0 { pair.0 } else { pair.1 }
}

fn set(pair: &mut (bool, bool), role: Role, value: bool) {
    if slot(role) == 0 { pair.0 = value } else { pair.1 = value }
}

impl Game {
    /// A player connected with the join code; the other is told, and the newcomer gets what its view
    /// of a running heist needs ([`Game::catch_up`]).
    pub fn join(&mut self, role: Role) {
        self.arrive(role);
        self.event(GameEvent::Joined(role));
        self.catch_up(role);
    }

    /// A dropped player took their kept seat back (the network checked the seat ticket); the other is
    /// told, and the one back gets what their view needs ([`Game::catch_up`]).
    pub fn resume(&mut self, role: Role) {
        self.arrive(role);
        self.event(GameEvent::Resumed(role));
        self.catch_up(role);
    }

    fn arrive(&mut self, role: Role) {
        set(&mut self.present, role, true);
        self.kept[slot(role)] = None;
        self.joined_once = true;
    }

    /// What a player's view needs that no replicated state carries, sent to them alone: for Phantom in
    /// a running heist, the briefings and the copy on the bench; for Vive, a fresh move numbering (his
    /// new connection numbers from 1, so the last move applied is forgotten, and with it any queued).
    fn catch_up(&mut self, role: Role) {
        match role {
            Role::Vive => {
                self.vive.inputs.clear();
                self.vive.last_input_seq = 0;
                self.vive.move_credit = 0;
            }
            Role::Phantom if self.phase == Phase::Heist => {
                let briefings = self.targets.iter().map(|t| t.briefing.clone()).collect();
                self.outgoing.push(Outgoing::To(Role::Phantom, ServerMsg::Briefings(briefings)));
                if let Some(copy) = self.workbench.and_then(|id| self.workbench_copy(id)) {
                    self.outgoing.push(Outgoing::To(Role::Phantom, ServerMsg::Workbench(copy)));
                }
            }
            Role::Phantom => {}
        }
    }

    /// A player disconnected (`dropped`: the connection was lost rather than closed); the other is told.
    /// A dropped player's seat is kept for them for [`rules::SEAT_HOLD_S`].
    pub fn leave(&mut self, role: Role, dropped: bool) {
        set(&mut self.present, role, false);
        set(&mut self.ready, role, false);
        set(&mut self.rematch, role, false);
        if dropped && !self.closed {
            self.kept[slot(role)] = Some(0.0);
        }
        self.event(GameEvent::Left { role, dropped });
    }

    /// True while `role`'s seat is kept for the player who dropped from it.
    pub fn is_seat_kept(&self, role: Role) -> bool {
        self.kept[slot(role)].is_some()
    }

    /// Seconds `role`'s kept seat stays kept at most (0 when it is not kept).
    pub fn seat_kept_for_s(&self, role: Role) -> f32 {
        self.kept[slot(role)].map_or(0.0, |t| (rules::SEAT_HOLD_S - t).max(0.0))
    }

    /// True while a running heist stands still for a missing player: the timer, the guards and every
    /// action wait (Vive's moves are acknowledged and dropped, so his client stands him where he is).
    pub fn is_paused(&self) -> bool {
        self.phase == Phase::Heist && self.present != (true, true)
    }

    /// True while the round has not ended.
    pub fn is_running(&self) -> bool {
        matches!(self.phase, Phase::Lobby | Phase::Heist)
    }

    /// Whether Vive could perceive guard `i` now: in a clear line within [`rules::VIVE_SIGHT_RANGE`], or
    /// within earshot of his footsteps ([`rules::GUARD_STEP_LOUDNESS`] along the door path). Only such
    /// guards are replicated to Vive's client; Phantom's status readout keeps them all.
    pub fn vive_perceives(&self, i: usize) -> bool {
        let (Some(guard), me) = (self.guards.get(i), self.vive.position) else { return false };
        let seen =
            guard.position.distance(me) <= rules::VIVE_SIGHT_RANGE && self.walls.line_of_sight(me, guard.position);
        seen || self.nav.heard_margin(guard.position, me, rules::GUARD_STEP_LOUDNESS) > 0.0
    }

    /// Seconds the session has been idle (after a result, or with nobody in it after someone was).
    pub fn idle_s(&self) -> f32 {
        self.idle_s
    }

    fn idle_limit_s(&self) -> f32 {
        self.options.idle_end_s.unwrap_or(SESSION_IDLE_S)
    }

    /// Applies one message from a player; a refusal changes nothing.
    pub fn apply(&mut self, role: Role, msg: &ClientMsg) -> Result<(), Refusal> {
        verify(role, self.phase, msg)?;
        if self.is_paused() {
            match msg {
                ClientMsg::Vive(ViveMsg::Move { seq, .. }) => {
                    if *seq > self.vive.last_input_seq {
                        self.vive.inputs.clear();
                        self.vive.last_input_seq = *seq;
                    }
                    return Ok(());
                }
                ClientMsg::Vive(ViveMsg::WarningSeen(_)) => {}
                ClientMsg::Vive(_) | ClientMsg::Phantom(PhantomMsg::Verdict { .. }) => return Err(Refusal::Paused),
                _ => {}
            }
        }
        match msg {
            ClientMsg::Lobby(LobbyMsg::Ready) => {
                set(&mut self.ready, role, true);
                self.start_if_ready();
                Ok(())
            }
            ClientMsg::Lobby(LobbyMsg::Rematch) => {
                if !get(self.rematch, role) {
                    set(&mut self.rematch, role, true);
                    self.event(GameEvent::RematchAsked(role));
                }
                self.start_round_if_agreed();
                Ok(())
            }
            // The network layer closes the connection; `leave` follows from it.
            ClientMsg::Lobby(LobbyMsg::Leave) => Ok(()),
            ClientMsg::Vive(m) => self.apply_vive(m),
            ClientMsg::Phantom(m) => self.apply_phantom(m),
            ClientMsg::Malformed(_) => unreachable!("verify refuses malformed messages"),
        }
    }

    fn start_if_ready(&mut self) {
        if self.phase == Phase::Lobby && self.present == (true, true) && self.ready == (true, true) {
            self.set_phase(Phase::Heist);
            let briefings = self.targets.iter().map(|t| t.briefing.clone()).collect();
            self.outgoing.push(Outgoing::To(Role::Phantom, ServerMsg::Briefings(briefings)));
        }
    }

    /// After a result, once both players are there and have asked: a new round on the next seed, same
    /// level, roles and options. Vive's input numbering carries on, so his client's next move counts.
    fn start_round_if_agreed(&mut self) {
        if self.is_running() || self.closed || self.present != (true, true) || self.rematch != (true, true) {
            return;
        }
        let mut options = self.options.clone();
        options.seed = if self.options.random_rounds { rand::random() } else { next_round_seed(self.seed) };
        let mut next = Game::new(self.level.clone(), &options);
        next.options = self.options.clone();
        next.round = self.round + 1;
        next.present = self.present;
        next.joined_once = true;
        next.ready = (true, true);
        next.vive.last_input_seq = self.vive.last_input_seq;
        next.outgoing = std::mem::take(&mut self.outgoing);
        next.draining = self.draining;
        *self = next;
        self.event(GameEvent::RoundStarted(self.round));
        self.start_if_ready();
    }

    /// The server is shutting down: tells both players that a heist under way may go on for `within_s`
    /// more seconds at most, and closes the session as soon as none is (at once in the lobby or after a
    /// result). The server closes it at the limit itself. Once only.
    pub fn drain(&mut self, within_s: u32) {
        if self.draining {
            return;
        }
        self.draining = true;
        self.event(GameEvent::ServerClosing { within_s });
    }

    /// Seats kept for players who dropped (0 to 2).
    pub fn kept_seats(&self) -> usize {
        self.kept.iter().filter(|k| k.is_some()).count()
    }

    /// Advances the session by `dt` seconds.
    pub fn step(&mut self, dt: f32) {
        self.keep_seats(dt);
        if self.draining && self.phase != Phase::Heist {
            self.closed = true;
        }
        match self.phase {
            Phase::Lobby => {
                self.start_if_ready();
                // A lobby waits for its players; once someone came and everyone left, it idles.
                let deserted = self.present == (false, false) && (self.joined_once || self.options.ends_unjoined);
                self.idle(dt, deserted);
            }
            Phase::Heist => self.step_heist(dt),
            Phase::Won | Phase::Lost(_) => {
                if self.present == (false, false) && self.kept == [None, None] {
                    self.closed = true;
                }
                self.idle(dt, true);
            }
        }
    }

    /// Counts the time kept seats have waited; one that waited [`rules::SEAT_HOLD_S`] is given up (and a
    /// running heist is lost, abandoned).
    fn keep_seats(&mut self, dt: f32) {
        for role in [Role::Vive, Role::Phantom] {
            let Some(waited) = self.kept[slot(role)].as_mut() else { continue };
            *waited += dt;
            if *waited >= rules::SEAT_HOLD_S {
                self.kept[slot(role)] = None;
                self.event(GameEvent::GaveUp(role));
                if self.phase == Phase::Heist {
                    self.set_phase(Phase::Lost(LossReason::Abandoned));
                }
            }
        }
    }

    /// Counts idle time while `idle`, warns once a minute before the end, and closes the session at the limit.
    fn idle(&mut self, dt: f32, idle: bool) {
        if !idle || self.closed {
            self.idle_s = 0.0;
            self.warned_ending = false;
            return;
        }
        self.idle_s += dt;
        let limit = self.idle_limit_s();
        if !self.warned_ending && limit > ENDING_WARNING_S && self.idle_s >= limit - ENDING_WARNING_S {
            self.warned_ending = true;
            self.event(GameEvent::EndingSoon(ENDING_WARNING_S as u32));
        }
        if self.idle_s >= limit {
            self.closed = true;
        }
    }

    fn step_heist(&mut self, dt: f32) {
        if self.is_paused() {
            // A kept seat waits for its player (`keep_seats`); a seat left on purpose waits for anyone.
            if self.kept == [None, None] {
                self.absent_s += dt;
                if self.absent_s >= ABANDON_GRACE_S {
                    self.set_phase(Phase::Lost(LossReason::Abandoned));
                }
            }
            return;
        }
        self.absent_s = 0.0;
        self.elapsed_s += dt;
        self.time_left_s = (self.time_left_s - dt).max(0.0);
        self.move_vive(dt);
        self.step_guards(dt);
        self.noises.clear();
        if self.time_left_s <= 0.0 && self.phase == Phase::Heist {
            self.set_phase(Phase::Lost(LossReason::Time));
        }
    }

    /// Messages produced since the last call, in order.
    pub fn drain_outgoing(&mut self) -> std::vec::Drain<'_, Outgoing> {
        self.outgoing.drain(..)
    }

    fn set_phase(&mut self, phase: Phase) {
        if self.phase != phase {
            self.phase = phase;
            self.event(GameEvent::PhaseChanged(phase));
        }
    }

    fn event(&mut self, event: GameEvent) {
        self.outgoing.push(Outgoing::All(ServerMsg::Event(event)));
    }

    fn noise(&mut self, kind: NoiseKind, position: Vec2, loudness: f32) {
        self.noises.push((position, loudness));
        self.event(GameEvent::Noise { kind, position, loudness });
    }

    fn raise_alarm(&mut self) {
        self.alarm = (self.alarm + 1).min(rules::ALARM_LOCKDOWN);
        self.event(GameEvent::Alarm(self.alarm));
        let at = self.level.workbench;
        self.noise(NoiseKind::Alarm, at, 0.0);
        if self.alarm >= rules::ALARM_LOCKDOWN {
            self.set_phase(Phase::Lost(LossReason::Alarm));
        }
    }

    /// Applies one queued input per tick (more when catching up on banked credit): the server moves
    /// the body exactly as the client predicted it, input by input, whatever the network did to their
    /// timing. With no input waiting, the body stands.
    fn move_vive(&mut self, dt: f32) {
        let before = self.vive.position;
        self.vive.move_credit = (self.vive.move_credit + 1).min(MAX_MOVE_CREDIT);
        let mut applied = 0;
        while applied < MAX_INPUTS_PER_TICK && self.vive.move_credit > 0 && self.apply_next_input(dt) {
            applied += 1;
        }
        self.vive.velocity = (self.vive.position - before) / dt.max(1e-6);
    }

    /// Moves the body by the oldest queued input, spending a tick of credit; false when none waits.
    /// Every running input counts towards footsteps, however it was applied.
    fn apply_next_input(&mut self, dt: f32) -> bool {
        let Some(input) = self.vive.inputs.pop_front() else { return false };
        let from = self.vive.position;
        self.vive.position = self.walls.move_body(from, input.direction, input.speed, dt);
        self.vive.stance = input.stance;
        self.vive.facing = input.facing;
        self.vive.last_input_seq = input.seq;
        self.vive.move_credit -= 1;
        if input.stance == Stance::Running && self.vive.position.distance(from) > 0.5 * dt {
            self.vive.footstep_timer -= dt;
            if self.vive.footstep_timer <= 0.0 {
                self.vive.footstep_timer = 0.5;
                let at = self.vive.position;
                self.noise(NoiseKind::Footsteps, at, rules::RUN_LOUDNESS);
            }
        }
        true
    }

    /// Applies the queued inputs now, as far as the move credit allows (it may run
    /// [`MAX_MOVE_DEBT`] ticks into debt, repaid by later ticks): an action arrived after them, so the
    /// player meant it from where they lead. However often actions come, the body never moves more
    /// ticks than have passed plus the banked credit.
    pub(super) fn fast_forward_inputs(&mut self, dt: f32) {
        while self.vive.move_credit > -MAX_MOVE_DEBT && self.apply_next_input(dt) {}
    }

    fn step_guards(&mut self, dt: f32) {
        let alarm = self.alarm;
        let t = self.tuning;
        let now = self.elapsed_s;
        // Radio calls that have come through: each answering guard gets his share of the spots.
        for (answering, at, limit) in self.radio.heard(now) {
            let orders = heist_shared::level::patrol::orders(&self.nav, at, limit, answering.len());
            for (&i, spots) in answering.iter().zip(orders) {
                self.guards[i].orders = Some(spots);
            }
        }
        self.lay_out_patrols();
        let unreported: Vec<(usize, Vec2)> = (self.cases.iter().enumerate())
            .filter(|(_, c)| c.broken && !c.reported)
            .map(|(i, c)| (i, c.position))
            .collect();
        for i in 0..self.guards.len() {
            let vive = guard::Body { position: self.vive.position, crouching: self.vive.stance == Stance::Crouching };
            let perception =
                guard::perceive(&self.guards[i], vive, &self.walls, &self.nav, &self.noises, &unreported, alarm, &t);
            let before = self.guards[i].alert;
            let acted = guard::think_and_act(&mut self.guards[i], &perception, &self.walls, &self.nav, alarm, &t, dt);
            let g = &self.guards[i];
            if g.alert != before {
                let event = GameEvent::GuardAlert { guard: g.id, alert: g.alert, position: g.position };
                self.event(event);
            }
            if acted.caught {
                self.caught_by = Some((i, self.vive.position));
                self.set_phase(Phase::Lost(LossReason::Caught));
                return;
            }
            if let Some(case) = acted.reported
                && !self.cases[case].reported
            {
                self.cases[case].reported = true;
                self.raise_alarm_for_evidence();
            }
            if let Some((about, at)) = acted.radio {
                self.radio_call(i, about, at);
            }
        }
    }

    /// Guard `caller` radios about `at`: both players hear it; those within range come after the delay.
    fn radio_call(&mut self, caller: usize, about: heist_shared::protocol::RadioAbout, at: Vec2) {
        if self.tuning.radio_range_m <= 0.0 {
            return;
        }
        let spots = about.search_spots();
        let answering = self.radio.call(&self.guards, caller, (at, spots), &self.tuning, self.elapsed_s);
        let g = &self.guards[caller];
        let answering = answering.iter().map(|&i| self.guards[i].id).collect();
        self.event(GameEvent::Radio { guard: g.id, about, at, from: g.position, answering });
    }

    /// A broken case was found: the alarm goes up one level, but never past the tuning's
    /// `evidence_alarm_cap` (only wrong verdicts lock the museum down).
    fn raise_alarm_for_evidence(&mut self) {
        if self.alarm < self.tuning.evidence_alarm_cap.min(rules::ALARM_LOCKDOWN - 1) {
            self.alarm += 1;
            self.event(GameEvent::Alarm(self.alarm));
        }
    }

    /// The rooms that still hold a copy of a target not yet secured, in an intact case.
    pub fn hot_rooms(&self) -> Vec<usize> {
        let mut rooms = Vec::new();
        self.hot_rooms_into(&mut rooms);
        rooms
    }

    /// [`Game::hot_rooms`] into `rooms`.
    fn hot_rooms_into(&self, rooms: &mut Vec<usize>) {
        let cases = self.items.iter().filter_map(|it| match (it.place, &it.truth) {
            (ItemPlace::InCase(c), Some(truth)) if !self.targets[truth.target].secured => {
                let case = self.cases.get(usize::from(c.0))?;
                (!case.broken).then_some(case.position)
            }
            _ => None,
        });
        heist_shared::level::patrol::hot_rooms_into(&self.nav, cases, rooms);
    }

    /// Lays the guards' patrols out for the alarm level and the rooms that hold targets, when either
    /// changed ([`heist_shared::level::patrol::alert_route`]).
    fn lay_out_patrols(&mut self) {
        let mut hot = std::mem::take(&mut self.hot_scratch);
        self.hot_rooms_into(&mut hot);
        if self.patrols_for.as_ref().is_some_and(|(alarm, rooms)| *alarm == self.alarm && *rooms == hot) {
            self.hot_scratch = hot;
            return;
        }
        for i in 0..self.guards.len() {
            let route = heist_shared::level::patrol::alert_route(&self.level, &self.nav, i, self.alarm, &hot);
            self.guards[i].set_route(route);
        }
        let before = self.patrols_for.replace((self.alarm, hot));
        self.hot_scratch = before.map(|(_, rooms)| rooms).unwrap_or_default();
    }

    /// The case with `id`, if it exists.
    fn case(&self, id: CaseId) -> Result<&Case, Refusal> {
        self.cases.get(usize::from(id.0)).ok_or(Refusal::Unknown)
    }

    /// The item with `id`, if it exists.
    fn item(&self, id: ItemId) -> Result<&Item, Refusal> {
        self.items.get(usize::from(id.0)).ok_or(Refusal::Unknown)
    }

    /// True when `role` is connected.
    pub fn is_present(&self, role: Role) -> bool {
        get(self.present, role)
    }
}

#[cfg(test)]
mod tests;
