//! What a guard senses this tick: Vive in sight, the loudest noise within earshot, a broken case in
//! sight that nobody has reported, and the spots a radio call asked him to search.

use glam::Vec2;
use heist_shared::level::{NavGraph, WallSet};
use heist_shared::rules::GuardTuning;

use super::{Guard, Perception};

/// What a guard can sense of Vive's body: where it is and whether he crouches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Where, metres.
    pub position: Vec2,
    /// Crouching (seen nearer only).
    pub crouching: bool,
}

/// Sight and hearing for one guard. `unreported` are the broken cases nobody has reported yet
/// (index, position).
#[allow(clippy::too_many_arguments)]
pub fn perceive(
    guard: &Guard,
    vive: Body,
    walls: &WallSet,
    nav: &NavGraph,
    noises: &[(Vec2, f32)],
    unreported: &[(usize, Vec2)],
    alarm: u8,
    t: &GuardTuning,
) -> Perception {
    let sees_vive =
        guard.in_cone(vive.position, vive.crouching, alarm, t) && walls.line_of_sight(guard.position, vive.position);
    let hearing = t.hearing_at(alarm);
    let heard = noises
        .iter()
        .map(|&(p, loud)| (p, nav.heard_margin(p, guard.position, loud * hearing)))
        .filter(|(_, margin)| *margin > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(p, _)| p);
    // Shattered glass is seen like a standing person (not a crouching one) within the cone.
    let evidence = unreported
        .iter()
        .filter(|(_, at)| guard.in_cone(*at, false, alarm, t) && walls.line_of_sight(guard.position, *at))
        .min_by(|a, b| guard.position.distance(a.1).total_cmp(&guard.position.distance(b.1)))
        .copied();
    Perception {
        sees_vive,
        vive_at: vive.position,
        vive_distance: guard.position.distance(vive.position),
        heard,
        evidence,
        radioed: guard.orders.clone(),
    }
}
