//! Practice at the workbench, offline: the copies of one artifact are placed one after another, the
//! briefing is read, and each verdict is answered right or wrong — to learn how the pieces feel (and to
//! show the spectator window without a server).
//!
//! You need this module for `client_haptic practice`. It fills the client core's [`Inbox`] and the
//! replicated views the way the server would, so the real client systems run unchanged.

use bevy::prelude::*;
use heist_client::Inbox;
use heist_shared::artifact::{self, ArtifactKind, CopyTraits};
use heist_shared::protocol::{
    ClientMsg, GameEvent, ItemId, ItemKind, ItemPlace, ItemView, PhantomMsg, Phase, Role, SessionView, VerdictOutcome,
    WorkbenchCopy,
};

/// The copies to practise on.
#[derive(Resource, Debug, Clone)]
pub struct Practice {
    /// Which artifact.
    pub kind: ArtifactKind,
    /// Build seed.
    pub seed: u64,
    /// The copies and which is real.
    pub copies: Vec<CopyTraits>,
    /// Index of the real one.
    pub real: usize,
    /// The copy on the bench.
    pub next: usize,
    /// Right verdicts so far.
    pub right: u32,
    /// Wrong verdicts so far.
    pub wrong: u32,
}

impl Practice {
    /// The copies of `kind` for `seed`.
    pub fn new(kind: ArtifactKind, seed: u64) -> Self {
        let (copies, real) = artifact::generate_copies(kind, seed, 3);
        Self { kind, seed, copies, real, next: 0, right: 0, wrong: 0 }
    }

    /// True once every copy was judged.
    pub fn finished(&self) -> bool {
        self.next >= self.copies.len()
    }
}

/// Runs practice (add instead of the client core's network plugin).
pub struct PracticePlugin;

impl Plugin for PracticePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Inbox>()
            .add_message::<ClientMsg>()
            .add_systems(Startup, set_up)
            .add_systems(Update, answer);
    }
}

fn place(p: &Practice, inbox: &mut Inbox) {
    let traits = &p.copies[p.next];
    let mesh = artifact::build_mesh(traits, p.seed);
    inbox.workbench = Some(WorkbenchCopy { item: ItemId(p.next as u16), mesh, material: traits.material.material() });
}

fn set_up(mut commands: Commands, p: Res<Practice>, mut inbox: ResMut<Inbox>) {
    inbox.role = Some(Role::Phantom);
    inbox.briefings = vec![artifact::briefing(&p.copies[p.real])];
    commands.spawn(SessionView {
        phase: Phase::Heist,
        time_left_s: 600.0,
        alarm: 0,
        targets: vec![(p.kind, false)],
        present: (true, true),
        difficulty: Default::default(),
    });
    for i in 0..p.copies.len() {
        let kind = ItemKind::Copy { artifact: p.kind, look: artifact::look(p.kind) };
        commands.spawn(ItemView { id: ItemId(i as u16), kind, place: ItemPlace::Workbench });
    }
    inbox.events.push(GameEvent::PhaseChanged(Phase::Heist));
    place(&p, &mut inbox);
}

/// Answers each verdict as the server would, then places the next copy.
fn answer(mut verdicts: MessageReader<ClientMsg>, mut p: ResMut<Practice>, mut inbox: ResMut<Inbox>) {
    for msg in verdicts.read() {
        let ClientMsg::Phantom(PhantomMsg::Verdict { item, real }) = msg else { continue };
        if item.0 as usize != p.next || p.finished() {
            continue;
        }
        let truth = p.next == p.real;
        let outcome = match (truth, *real) {
            (true, true) => VerdictOutcome::Secured,
            (false, false) => VerdictOutcome::Discarded,
            _ => VerdictOutcome::Wrong,
        };
        if outcome == VerdictOutcome::Wrong {
            p.wrong += 1
        } else {
            p.right += 1
        }
        inbox.events.push(GameEvent::Verdict { item: *item, declared_real: *real, outcome });
        // Practice moves on after every verdict, right or wrong.
        p.next += 1;
        // The last one's result is said by the app, after the verdict's answer.
        if !p.finished() {
            place(&p, &mut inbox);
        }
    }
}
