//! On a client, the packed replicated lists ([`Cases`], [`Items`], [`Guards`]) spread into one local
//! entity per case, item and guard carrying its view ([`CaseView`], [`ItemView`], [`GuardView`]), so
//! game code queries one entity per object while the server replicates a few entities per session.
//!
//! A view's entity is spawned when its id first arrives, updated in place (change detection fires only
//! when the view changed) and despawned when no replicated list carries its id any more: a guard Vive
//! stops perceiving, or everything once the connection's entities are gone.

use std::collections::{HashMap, HashSet};
use std::hash::Hash;

use bevy::prelude::*;
use bevy_replicon::client::{ClientSystems, Remote};

use super::ids::{CaseId, GuardId, ItemId};
use super::replicated::{CaseView, Cases, GuardView, Guards, ItemView, Items};

/// A replicated list of views, each with an id.
pub trait Spread: Component {
    /// One object's view, as game code queries it.
    type View: Component<Mutability = bevy::ecs::component::Mutable> + Clone + PartialEq;
    /// What tells the objects apart.
    type Id: Copy + Eq + Hash + Send + Sync + 'static;
    /// The views in the list.
    fn views(&self) -> &[Self::View];
    /// A view's id.
    fn id(view: &Self::View) -> Self::Id;
}

impl Spread for Cases {
    type View = CaseView;
    type Id = CaseId;
    fn views(&self) -> &[CaseView] {
        &self.0
    }
    fn id(view: &CaseView) -> CaseId {
        view.id
    }
}

impl Spread for Items {
    type View = ItemView;
    type Id = ItemId;
    fn views(&self) -> &[ItemView] {
        &self.0
    }
    fn id(view: &ItemView) -> ItemId {
        view.id
    }
}

impl Spread for Guards {
    type View = GuardView;
    type Id = GuardId;
    fn views(&self) -> &[GuardView] {
        &self.0
    }
    fn id(view: &GuardView) -> GuardId {
        view.id
    }
}

/// `PreUpdate`, right after replicon's receive: the lists spread into their local entities.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct SpreadSystems;

pub(super) fn add_systems(app: &mut App) {
    app.configure_sets(PreUpdate, SpreadSystems.after(ClientSystems::Receive))
        .add_systems(PreUpdate, (spread::<Cases>, spread::<Items>, spread::<Guards>).in_set(SpreadSystems));
}

/// The local entities spread from the lists of type `P`, by id.
struct Spreads<P: Spread> {
    entities: HashMap<P::Id, Entity>,
    seen: HashSet<P::Id>,
}

impl<P: Spread> Default for Spreads<P> {
    fn default() -> Self {
        Self { entities: HashMap::new(), seen: HashSet::new() }
    }
}

/// Spreads every replicated list of type `P` (only received ones: a server's own lists stay packed).
fn spread<P: Spread>(
    mut commands: Commands,
    mut spreads: Local<Spreads<P>>,
    lists: Query<Ref<P>, With<Remote>>,
    mut removed: RemovedComponents<P>,
    mut views: Query<&mut P::View>,
) {
    let removed = removed.read().count() > 0;
    if !removed && !lists.iter().any(|l| l.is_changed()) {
        return;
    }
    let Spreads { entities, seen } = &mut *spreads;
    seen.clear();
    for list in &lists {
        for view in list.views() {
            let id = P::id(view);
            if !seen.insert(id) {
                continue; // in two lists at once: one entity
            }
            match entities.get(&id).and_then(|e| views.get_mut(*e).ok()) {
                Some(mut local) => {
                    local.set_if_neq(view.clone());
                }
                None => {
                    entities.insert(id, commands.spawn(view.clone()).id());
                }
            }
        }
    }
    entities.retain(|id, entity| {
        let keep = seen.contains(id);
        if !keep {
            commands.entity(*entity).try_despawn();
        }
        keep
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{GuardAlert, GuardId};

    fn guard(id: u16, x: f32) -> GuardView {
        GuardView {
            id: GuardId(id),
            name: format!("g{id}"),
            position: Vec2::new(x, 0.0),
            facing: 0.0,
            alert: GuardAlert::Patrolling,
        }
    }

    fn app() -> App {
        let mut app = App::new();
        app.add_systems(Update, spread::<Guards>);
        app
    }

    fn local_guards(app: &mut App) -> Vec<(u16, f32)> {
        let world = app.world_mut();
        let mut all: Vec<(u16, f32)> =
            world.query::<&GuardView>().iter(world).map(|g| (g.id.0, g.position.x)).collect();
        all.sort_by_key(|g| g.0);
        all
    }

    #[test]
    fn a_received_list_becomes_one_entity_per_guard_updated_in_place_and_despawned_when_no_list_has_it() {
        let mut app = app();
        let seen = app.world_mut().spawn((Remote, Guards(vec![guard(0, 1.0)]))).id();
        let all = app.world_mut().spawn((Remote, Guards(vec![guard(0, 1.0), guard(1, 2.0), guard(2, 3.0)]))).id();
        app.update();
        assert_eq!(local_guards(&mut app), [(0, 1.0), (1, 2.0), (2, 3.0)], "a guard in both lists is one entity");
        let first = app.world_mut().query::<(Entity, &GuardView)>().iter(app.world()).find(|(_, g)| g.id.0 == 1);
        let first = first.map(|(e, _)| e);

        app.world_mut().entity_mut(all).insert(Guards(vec![guard(0, 1.0), guard(1, 5.0)]));
        app.update();
        assert_eq!(local_guards(&mut app), [(0, 1.0), (1, 5.0)], "moved in place; the one no list has is gone");
        let now = app.world_mut().query::<(Entity, &GuardView)>().iter(app.world()).find(|(_, g)| g.id.0 == 1);
        assert_eq!(now.map(|(e, _)| e), first, "the same entity, updated");

        app.world_mut().entity_mut(all).despawn();
        app.update();
        assert_eq!(local_guards(&mut app), [(0, 1.0)], "what the remaining list holds");
        app.world_mut().entity_mut(seen).despawn();
        app.update();
        assert!(local_guards(&mut app).is_empty(), "no list, no guard");
    }

    #[test]
    fn a_list_that_was_not_received_is_not_spread() {
        let mut app = app();
        app.world_mut().spawn(Guards(vec![guard(0, 1.0)]));
        app.update();
        assert!(local_guards(&mut app).is_empty(), "a server's own lists stay packed");
    }
}
