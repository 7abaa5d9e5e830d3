//! The level format: a museum described as data (`assets/levels/*.ron`).
//!
//! You need this module to load or validate a level, and for everything that asks where walls, doors,
//! cases and patrol routes are. Loading checks every reference and every geometric rule, and a bad file
//! gives an error naming the file, the place and what is wrong.

mod geometry;
mod nav;
pub mod patrol;
mod validate;

pub use geometry::{Segment, WallSet};
pub use nav::NavGraph;

use std::path::{Path, PathBuf};

use glam::Vec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::artifact::ArtifactKind;

/// A whole level, as stored in a `.ron` file. Coordinates are metres on the floor plane (x, z).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Level {
    /// Display name, spoken to the players.
    pub name: String,
    /// Heist duration in seconds of game time.
    pub time_limit_s: f32,
    /// Axis-aligned rectangular rooms.
    pub rooms: Vec<Room>,
    /// Doors joining two rooms that share a wall.
    pub doors: Vec<Door>,
    /// Display cases; each may hold one copy.
    pub cases: Vec<DisplayCase>,
    /// Artifacts to steal: each has one real copy and `copies - 1` fakes.
    pub targets: Vec<TargetSpec>,
    /// Loose objects Vive can pick up and throw.
    #[serde(default)]
    pub props: Vec<Vec2>,
    /// Guards with their patrol routes.
    pub guards: Vec<GuardSpec>,
    /// Phantom's workbench (where copies are placed).
    pub workbench: Vec2,
    /// Where Vive starts.
    pub vive_spawn: Vec2,
    /// The museum's exit.
    pub exit: Vec2,
    /// The guards' tuning per difficulty, where this level wants its own (default: the built-in ones).
    #[serde(default)]
    pub difficulties: crate::rules::DifficultyTable,
}

/// A rectangular room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Room {
    /// Unique name.
    pub id: String,
    /// Minimum corner (x, z), metres.
    pub min: Vec2,
    /// Maximum corner (x, z), metres.
    pub max: Vec2,
}

impl Room {
    /// Which wall this room shares with `b` at `p`: `Some(true)` for a wall at constant x, `Some(false)`
    /// at constant z.
    pub(crate) fn shared_wall_axis(&self, b: &Room, p: Vec2) -> Option<bool> {
        let a = self;
        const EPS: f32 = 1e-3;
        let on_x = |r: &Room| (p.x - r.min.x).abs() < EPS || (p.x - r.max.x).abs() < EPS;
        let on_z = |r: &Room| (p.y - r.min.y).abs() < EPS || (p.y - r.max.y).abs() < EPS;
        let within_z = |r: &Room| p.y > r.min.y && p.y < r.max.y;
        let within_x = |r: &Room| p.x > r.min.x && p.x < r.max.x;
        if on_x(a) && on_x(b) && within_z(a) && within_z(b) {
            Some(true)
        } else if on_z(a) && on_z(b) && within_x(a) && within_x(b) {
            Some(false)
        } else {
            None
        }
    }

    /// True when `p` lies inside the room (inclusive, with `margin` metres shaved off every side).
    pub fn contains(&self, p: Vec2, margin: f32) -> bool {
        p.x >= self.min.x + margin
            && p.x <= self.max.x - margin
            && p.y >= self.min.y + margin
            && p.y <= self.max.y - margin
    }

    /// Centre of the room.
    pub fn centre(&self) -> Vec2 {
        (self.min + self.max) * 0.5
    }
}

/// A door in the wall shared by two rooms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Door {
    /// The two rooms it joins (by id).
    pub between: (String, String),
    /// Centre of the opening, on the shared wall.
    pub at: Vec2,
    /// Width of the opening, metres (default 1.4).
    #[serde(default = "default_door_width")]
    pub width: f32,
    /// Closed doors block sight and muffle sound; anyone can walk through them.
    #[serde(default = "default_true")]
    pub open: bool,
    /// Fraction of loudness that passes the door when it is closed, 0..=1 (default 0.35).
    #[serde(default = "default_attenuation")]
    pub attenuation: f32,
}

fn default_door_width() -> f32 {
    1.4
}
fn default_true() -> bool {
    true
}
fn default_attenuation() -> f32 {
    0.35
}

/// A glass display case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplayCase {
    /// Unique name.
    pub id: String,
    /// Position, metres.
    pub at: Vec2,
}

/// One target artifact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetSpec {
    /// Which artifact.
    pub kind: ArtifactKind,
    /// Number of copies including the real one (>= 3).
    pub copies: usize,
}

/// A guard and the route it patrols (a closed loop of waypoints).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GuardSpec {
    /// Display name ("Bruno").
    pub name: String,
    /// Waypoints visited in order, then back to the first.
    pub route: Vec<Vec2>,
}

/// Why a level could not be loaded.
#[derive(Debug, Error)]
pub enum LevelError {
    /// The file could not be read.
    #[error("{path}: cannot read the level file")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not valid RON for a level.
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser expected.
        message: String,
    },
    /// The file parses but breaks a rule of the level format.
    #[error("{path}: {place}: {problem}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Where in the level ("doors[2]", "guards[0].route[3]").
        place: String,
        /// What is wrong.
        problem: String,
    },
}

/// Minimum counts the game design asks of a playable museum.
const MIN_ROOMS: usize = 5;
const MIN_GUARDS: usize = 3;
const MIN_TARGETS: usize = 3;

impl Level {
    /// Reads and validates a level file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, LevelError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| LevelError::Io { path: path.to_owned(), source })?;
        Self::parse(&text, path)
    }

    /// Parses and validates level text; `path` is used in error messages only.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Self, LevelError> {
        let path = path.as_ref();
        let level: Level = ron::from_str(text).map_err(|e| LevelError::Syntax {
            path: path.to_owned(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        level.validate().map_err(|(place, problem)| LevelError::Invalid { path: path.to_owned(), place, problem })?;
        Ok(level)
    }

    /// The museum shipped with the game (`assets/levels/museum.ron`), embedded at compile time.
    pub fn museum() -> Self {
        Self::parse(include_str!("../../../../assets/levels/museum.ron"), "assets/levels/museum.ron")
            .unwrap_or_else(|e| panic!("the embedded museum level is invalid: {e}"))
    }

    /// Index of the room containing `p` (first match), if any.
    pub fn room_at(&self, p: Vec2) -> Option<usize> {
        self.rooms.iter().position(|r| r.contains(p, 0.0))
    }

    /// Index of a room by id.
    pub fn room_index(&self, id: &str) -> Option<usize> {
        self.rooms.iter().position(|r| r.id == id)
    }

    /// Total number of copies over all targets.
    pub fn copy_count(&self) -> usize {
        self.targets.iter().map(|t| t.copies).sum()
    }

    /// The guards' tuning on difficulty `d` in this level.
    pub fn tuning(&self, d: crate::rules::Difficulty) -> crate::rules::GuardTuning {
        self.difficulties.tuning(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_museum_is_valid_and_big_enough() {
        let level = Level::museum();
        assert!(level.rooms.len() >= 5 && level.guards.len() >= 3 && level.targets.len() >= 3);
    }

    #[test]
    fn a_syntax_error_names_file_line_and_column() {
        let e = Level::parse("Level(name: \"x\", time_limit_s: ", "bad.ron").unwrap_err();
        let text = e.to_string();
        assert!(text.starts_with("bad.ron:1:"), "{text}");
    }

    #[test]
    fn a_door_between_unknown_rooms_is_named() {
        let text = include_str!("../../../../assets/levels/museum.ron").replacen(
            "between: (\"lobby\"",
            "between: (\"attic\"",
            1,
        );
        let e = Level::parse(&text, "m.ron").unwrap_err().to_string();
        assert!(e.contains("doors[") && e.contains("unknown room `attic`"), "{e}");
    }

    #[test]
    fn a_guard_waypoint_outside_the_museum_is_named() {
        let mut level = Level::museum();
        level.guards[1].route[0] = Vec2::new(500.0, 500.0);
        let (place, problem) = level.validate().unwrap_err();
        assert_eq!(place, "guards[1].route[0]");
        assert!(problem.contains("outside every room"));
    }

    #[test]
    fn too_few_cases_for_the_copies_is_refused() {
        let mut level = Level::museum();
        level.cases.truncate(2);
        let (place, _) = level.validate().unwrap_err();
        assert_eq!(place, "cases");
    }
}
