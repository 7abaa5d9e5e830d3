//! Building a session from a level and a seed: copies, their hidden truth, cases, guards.

use glam::Vec2;
use heist_shared::artifact;
use heist_shared::level::{Level, NavGraph, WallSet};
use heist_shared::protocol::{CaseId, GuardId, ItemId, ItemKind, ItemPlace, Phase};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

use super::guard::Guard;
use super::{Case, CopyTruth, Game, GameOptions, Item, Target, Vive};

impl Game {
    /// A new session in the lobby.
    pub fn new(level: Level, options: &GameOptions) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
        let walls = WallSet::new(&level);
        let nav = NavGraph::new(&level);

        // Copies first, each tagged with its truth; then shuffle so item ids and cases say nothing.
        let mut copies = Vec::new();
        let mut targets = Vec::new();
        for (t, spec) in level.targets.iter().enumerate() {
            let target_seed = artifact::target_seed(options.seed, t);
            let (traits, real_index) = artifact::generate_copies(spec.kind, target_seed, spec.copies);
            targets.push(Target { kind: spec.kind, briefing: artifact::briefing(&traits[real_index]), secured: false });
            for (c, tr) in traits.into_iter().enumerate() {
                let mesh = artifact::build_mesh(&tr, artifact::copy_mesh_seed(target_seed, c));
                let material = tr.material.material();
                let kind = ItemKind::Copy { artifact: spec.kind, look: artifact::look(spec.kind) };
                copies.push((kind, CopyTruth { target: t, traits: tr, real: c == real_index, mesh, material }));
            }
        }
        copies.shuffle(&mut rng);
        let mut case_order: Vec<usize> = (0..level.cases.len()).collect();
        case_order.shuffle(&mut rng);

        let mut items: Vec<Item> = copies
            .into_iter()
            .zip(&case_order)
            .map(|((kind, truth), &case)| Item {
                kind,
                place: ItemPlace::InCase(CaseId(case as u16)),
                truth: Some(truth),
            })
            .collect();
        items.extend(level.props.iter().map(|&p| Item {
            kind: ItemKind::Prop,
            place: ItemPlace::Floor(p),
            truth: None,
        }));

        let tuning = level.tuning(options.difficulty);
        let guards = level
            .guards
            .iter()
            .take(tuning.guards.unwrap_or(usize::MAX))
            .enumerate()
            .map(|(i, g)| Guard::new(GuardId(i as u16), g.name.clone(), g.route.clone()))
            .collect();
        let cases = level.cases.iter().map(|c| Case { position: c.at, broken: false, reported: false }).collect();
        let vive = Vive { position: level.vive_spawn, facing: 0.0, ..Default::default() };
        let time_left_s = options.time_limit_s.unwrap_or(level.time_limit_s * tuning.time_scale);

        Game {
            walls,
            nav,
            phase: Phase::Lobby,
            time_left_s,
            elapsed_s: 0.0,
            alarm: 0,
            vive,
            guards,
            difficulty: options.difficulty,
            tuning,
            cases,
            items,
            targets,
            workbench: None,
            present: (false, false),
            ready: (false, false),
            absent_s: 0.0,
            noises: Vec::new(),
            outgoing: Vec::new(),
            rng,
            radio: Default::default(),
            patrols_for: None,
            hot_scratch: Vec::new(),
            caught_by: None,
            level,
            seed: options.seed,
            round: 1,
            closed: false,
            draining: false,
            options: options.clone(),
            rematch: (false, false),
            kept: [None, None],
            idle_s: 0.0,
            warned_ending: false,
            joined_once: false,
            tool: Default::default(),
        }
    }
}

impl Game {
    /// The id of item number `index`.
    pub fn item_id(index: usize) -> ItemId {
        ItemId(index as u16)
    }

    /// Positions of items that lie on the floor (for tests and bots' sanity checks).
    pub fn floor_items(&self) -> impl Iterator<Item = (ItemId, Vec2)> + '_ {
        self.items.iter().enumerate().filter_map(|(i, it)| match it.place {
            ItemPlace::Floor(p) => Some((Self::item_id(i), p)),
            _ => None,
        })
    }

    /// A uniform random number in `0..1` from the session's seeded generator.
    pub fn random(&mut self) -> f32 {
        use rand::Rng;
        self.rng.random::<f32>()
    }
}
