//! The Phantom bot: judges the copy on the workbench from its geometry and material against the briefing.

use bevy::prelude::*;
use heist_client::Inbox;
use heist_shared::artifact::{self, ArtifactKind};
use heist_shared::protocol::{
    ClientMsg, GameEvent, ItemId, ItemKind, ItemView, LobbyMsg, PhantomMsg, Phase, SessionView, VerdictOutcome,
    WorkbenchCopy,
};

/// The Phantom bot's memory.
#[derive(Resource, Default, Debug)]
pub struct PhantomBrain {
    round: u32,
    ready_sent: bool,
    pending: Option<(WorkbenchCopy, f32)>,
    last_verdict: Option<(ItemId, bool)>,
    /// Verdicts given: (copy, declared real).
    pub verdicts: Vec<(ItemId, bool)>,
}

/// Plays Phantom: ready up, then judge every copy that lands on the workbench.
pub struct PhantomBotPlugin {
    /// Seconds spent "exploring" a copy before the verdict (default 2).
    pub think_s: f32,
}

impl Default for PhantomBotPlugin {
    fn default() -> Self {
        Self { think_s: 2.0 }
    }
}

#[derive(Resource)]
struct ThinkTime(f32);

impl Plugin for PhantomBotPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<PhantomBrain>()
            .insert_resource(ThinkTime(self.think_s))
            .add_systems(Update, (play, crate::rounds::ask_for_another_round));
    }
}

/// Decides real or fake from touchable data only: the features computed from the mesh and the material.
pub fn judge(kind: ArtifactKind, copy: &WorkbenchCopy, briefings: &[artifact::Briefing]) -> Option<bool> {
    let briefing = briefings.iter().find(|b| b.kind == kind)?;
    let observed = artifact::analyze(kind, &copy.mesh);
    Some(artifact::matches(briefing, &observed, &copy.material))
}

fn play(
    mut brain: ResMut<PhantomBrain>,
    mut inbox: ResMut<Inbox>,
    think: Res<ThinkTime>,
    time: Res<Time>,
    session: Query<&SessionView>,
    items: Query<&ItemView>,
    mut out: MessageWriter<ClientMsg>,
) {
    let Ok(session) = session.single() else { return };
    let round = inbox.current_round();
    if brain.round != round {
        // A new round: nothing of the last one's copies counts (the first round is ready already).
        *brain = PhantomBrain { round, ready_sent: brain.round != 0, ..Default::default() };
    }
    if session.phase == Phase::Lobby && !brain.ready_sent && inbox.role.is_some() {
        out.write(ClientMsg::Lobby(LobbyMsg::Ready));
        brain.ready_sent = true;
    }
    if session.phase != Phase::Heist {
        return;
    }
    // A wrong verdict leaves the copy on the bench: judge it again the other way.
    for event in std::mem::take(&mut inbox.events) {
        if let GameEvent::Verdict { item, declared_real, outcome: VerdictOutcome::Wrong } = event
            && brain.last_verdict == Some((item, declared_real))
        {
            out.write(ClientMsg::Phantom(PhantomMsg::Verdict { item, real: !declared_real }));
            brain.verdicts.push((item, !declared_real));
        }
    }
    if let Some(copy) = inbox.workbench.take() {
        brain.pending = Some((copy, think.0));
    }
    let Some((copy, left)) = brain.pending.as_mut() else { return };
    *left -= time.delta_secs();
    if *left > 0.0 {
        return;
    }
    let kind = items.iter().find(|i| i.id == copy.item).and_then(|i| match &i.kind {
        ItemKind::Copy { artifact, .. } => Some(*artifact),
        ItemKind::Prop => None,
    });
    let Some(kind) = kind else { return }; // replication of the item not here yet: try next frame
    let item = copy.item;
    let real = judge(kind, copy, &inbox.briefings).unwrap_or(false);
    out.write(ClientMsg::Phantom(PhantomMsg::Verdict { item, real }));
    brain.verdicts.push((item, real));
    brain.last_verdict = Some((item, real));
    brain.pending = None;
}
