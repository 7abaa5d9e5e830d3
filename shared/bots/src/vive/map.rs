//! What the Vive bot knows of the museum for the whole heist: the level, its room graph and walls, and
//! the patrols any player can work out. Built once when the level arrives; never cloned per frame.

use glam::Vec2;
use heist_shared::level::{Level, NavGraph, WallSet, patrol};
use heist_shared::protocol::{CaseView, ItemKind, ItemPlace, ItemView, SessionView};
use heist_shared::rules::GuardTuning;

use crate::spacetime::Grid;

/// The museum as the bot knows it.
pub(crate) struct Map {
    pub level: Level,
    pub nav: NavGraph,
    pub walls: WallSet,
    pub workbench: Vec2,
    /// The floor as cells, for ways through space and time.
    pub grid: Grid,
}

impl Map {
    pub fn new(level: &Level) -> Self {
        let walls = WallSet::new(level);
        let grid = Grid::new(level, &walls);
        Self { nav: NavGraph::new(level), walls, grid, workbench: level.workbench, level: level.clone() }
    }

    /// What the guards can do on the session's difficulty (the published numbers).
    pub fn tuning(&self, session: &SessionView) -> GuardTuning {
        self.level.tuning(session.difficulty)
    }

    /// Each guard's patrol now (by guard id), as any player can work it out: the level's routes, or at
    /// a raised alarm the ones through the rooms that still hold targets (`patrol::alert_route`, the
    /// same function the server moves its guards with).
    pub fn patrols(&self, session: &SessionView, cases: &[&CaseView], items: &[&ItemView]) -> Vec<Vec<Vec2>> {
        let secured: Vec<_> = session.targets.iter().filter(|t| t.1).map(|t| t.0).collect();
        let cases = items.iter().filter_map(|i| match (&i.kind, i.place) {
            (ItemKind::Copy { artifact, .. }, ItemPlace::InCase(c)) if !secured.contains(artifact) => {
                cases.iter().find(|cv| cv.id == c && !cv.broken).map(|cv| cv.position)
            }
            _ => None,
        });
        let hot = patrol::hot_rooms(&self.nav, cases);
        (0..self.level.guards.len())
            .map(|g| patrol::alert_route(&self.level, &self.nav, g, session.alarm, &hot))
            .collect()
    }

    /// Places worth fleeing to: each room's centre and the middles of its quarters.
    pub fn refuge_spots(&self) -> impl Iterator<Item = Vec2> + '_ {
        self.level.rooms.iter().flat_map(|r| {
            let (c, h) = ((r.min + r.max) * 0.5, (r.max - r.min) * 0.25);
            [c, c + h, c - h, c + Vec2::new(h.x, -h.y), c + Vec2::new(-h.x, h.y)]
        })
    }
}
