//! Bot input: the Vive bot's brain (`heist_bots`) plays through this client's own logic.
//!
//! The brain sees the replicated museum with the body where this client predicts it, and its decision
//! becomes an [`Intent`] like a player's input would — so prediction, reconciliation and the intent
//! pipeline are the ones a player uses. `--headless --bot` runs exactly this without rendering.

use bevy::prelude::*;
use heist_bots::{Seen, ViveBrain, ViveStyle};

use crate::intent::{Action, Intent, IntentSystems};
use crate::state::ViveState;

/// The bot's play style (default careful).
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct BotStyle(pub ViveStyle);

/// Adds the brain and the system that thinks once a frame.
pub struct BotInputPlugin;

impl Plugin for BotInputPlugin {
    fn build(&self, app: &mut App) {
        let style = app.world().get_resource::<BotStyle>().copied().unwrap_or_default().0;
        app.insert_resource(ViveBrain::new(style)).add_systems(RunFixedMainLoop, think.in_set(IntentSystems::Gather));
    }
}

fn think(mut brain: ResMut<ViveBrain>, mut intent: ResMut<Intent>, state: Res<ViveState>, time: Res<Time>, seen: Seen) {
    let Some(avatar) = seen.avatar() else { return };
    // The brain sees the body where the client predicts it.
    let mut me = avatar.clone();
    if let Some(p) = state.predictor.as_ref() {
        me.position = p.position();
    }
    me.facing = intent.facing;
    let Some(sight) = seen.sight(&me) else { return };
    let turn = brain.think(&sight, time.delta_secs());
    if turn.ready {
        intent.actions.push(Action::Ready);
    }
    if let Some(action) = turn.action.as_ref().and_then(Action::from_message) {
        intent.actions.push(action);
    }
    if let Some((direction, gait, facing)) = turn.movement {
        intent.movement = direction;
        intent.gait = gait;
        intent.facing = facing;
    }
}
