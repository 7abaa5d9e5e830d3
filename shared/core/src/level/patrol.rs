//! Where guards walk besides their public routes: the patrol they switch to once the alarm is raised,
//! and the spots they search around where Vive was seen. Public knowledge, computed alike by the server
//! (which moves the guards) and by the Vive bot (which forecasts them), from what both can see.
//!
//! You need this module to change how guards cover the museum under alarm or how they search.

use glam::Vec2;

use super::{Level, NavGraph};

/// The route guard `guard` of `level` patrols at alarm level `alarm`, given the `hot` rooms (rooms that
/// hold a copy of a target not yet secured, in an intact case). At alarm 0 it is the level's route; from
/// alarm 1 the guard also walks through the centre of the hot room nearest its route, if its route does
/// not pass through a hot room already, so more guards watch the galleries that still hold targets.
pub fn alert_route(level: &Level, nav: &NavGraph, guard: usize, alarm: u8, hot: &[usize]) -> Vec<Vec2> {
    let Some(spec) = level.guards.get(guard) else { return Vec::new() };
    let base = spec.route.clone();
    if alarm == 0 || hot.is_empty() || base.is_empty() {
        return base;
    }
    let on_route: Vec<usize> = base.iter().filter_map(|p| nav.room_at(*p)).collect();
    if on_route.iter().any(|r| hot.contains(r)) {
        return base;
    }
    // The hot room whose centre is the shortest walk from any waypoint, and that waypoint.
    let best = hot
        .iter()
        .filter_map(|&r| nav.room_centre(r).map(|c| (r, c)))
        .flat_map(|(_, c)| base.iter().enumerate().map(move |(i, w)| (nav.route_length(*w, c), i, c)))
        .filter(|(d, _, _)| d.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    match best {
        Some((_, i, centre)) => {
            let mut route = base;
            route.insert(i + 1, centre);
            route
        }
        None => base,
    }
}

/// The hot rooms: those that hold any of `cases` (the positions of the intact cases that still hold a
/// copy of a target not yet secured), each once, in room order. The server passes its cases, the Vive
/// bot the replicated ones, so both lay the alarm's routes out alike.
pub fn hot_rooms(nav: &NavGraph, cases: impl IntoIterator<Item = Vec2>) -> Vec<usize> {
    let mut rooms = Vec::new();
    hot_rooms_into(nav, cases, &mut rooms);
    rooms
}

/// [`hot_rooms`] into `rooms` (cleared first), so a caller asking every tick reuses one buffer.
pub fn hot_rooms_into(nav: &NavGraph, cases: impl IntoIterator<Item = Vec2>, rooms: &mut Vec<usize>) {
    rooms.clear();
    rooms.extend(cases.into_iter().filter_map(|at| nav.room_at(at)));
    rooms.sort_unstable();
    rooms.dedup();
}

/// The spots to search around `at`, nearest first: `at` itself, then the centres of the rooms next to
/// the room it is in; at most `limit`.
pub fn search_spots(nav: &NavGraph, at: Vec2, limit: usize) -> Vec<Vec2> {
    let mut spots = vec![at];
    if let Some(room) = nav.room_at(at) {
        let mut next: Vec<(f32, Vec2)> = nav
            .neighbours(room)
            .into_iter()
            .filter_map(|r| nav.room_centre(r))
            .map(|c| (nav.route_length(at, c), c))
            .collect();
        next.sort_by(|a, b| a.0.total_cmp(&b.0));
        spots.extend(next.into_iter().map(|(_, c)| c));
    }
    spots.truncate(limit.max(1));
    spots
}

/// The spots each guard answering a radio call about `at` searches, in the order they answer
/// (nearest to `at` first): the `limit` spots around it ([`search_spots`]) dealt round ([`share_of`]).
/// The server gives these orders; the Vive bot, which hears the call, works out the same.
pub fn orders(nav: &NavGraph, at: Vec2, limit: usize, answering: usize) -> Vec<Vec<Vec2>> {
    let spots = search_spots(nav, at, limit);
    (0..answering).map(|k| share_of(&spots, k, answering)).collect()
}

/// The share of `spots` searcher number `k` of `n` takes: the spots are dealt round, starting with
/// spot `k`, so two searchers never walk to the same spot first.
pub fn share_of(spots: &[Vec2], k: usize, n: usize) -> Vec<Vec2> {
    if spots.is_empty() {
        return Vec::new();
    }
    let n = n.max(1);
    let mine: Vec<Vec2> = spots.iter().skip(k % spots.len()).step_by(n).copied().collect();
    if mine.is_empty() { vec![spots[k % spots.len()]] } else { mine }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_radio_call_deals_the_spots_around_it_round_the_answering_guards() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        let at = Vec2::new(20.0, 5.0);
        let spots = search_spots(&nav, at, 4);
        assert_eq!(orders(&nav, at, 4, 2), vec![vec![spots[0], spots[2]], vec![spots[1], spots[3]]]);
        assert_eq!(orders(&nav, at, 4, 1), vec![spots.clone()], "one guard searches them all");
    }

    #[test]
    fn without_alarm_a_guard_walks_its_route_and_with_it_also_a_gallery_that_holds_targets() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        // Clara walks the sculpture hall and the treasury; the west gallery is off her round.
        let gallery = level.room_index("west_gallery").expect("room");
        let clara = 1;
        assert_eq!(alert_route(&level, &nav, clara, 0, &[gallery]), level.guards[clara].route);
        let alerted = alert_route(&level, &nav, clara, 1, &[gallery]);
        assert_eq!(alerted.len(), level.guards[clara].route.len() + 1);
        assert!(alerted.iter().any(|p| nav.room_at(*p) == Some(gallery)), "{alerted:?}");
        // A guard whose route already crosses a hot room keeps it.
        for crossed in ["sculpture_hall", "treasury"] {
            let room = level.room_index(crossed).expect("room");
            assert_eq!(alert_route(&level, &nav, clara, 2, &[room]), level.guards[clara].route, "{crossed}");
        }
    }

    #[test]
    fn the_search_starts_where_vive_was_seen_and_spreads_to_the_next_rooms_dealt_between_searchers() {
        let level = Level::museum();
        let nav = NavGraph::new(&level);
        let at = glam::Vec2::new(16.0, 15.0); // sculpture hall: next to the workshop, west gallery, treasury
        let spots = search_spots(&nav, at, 4);
        assert_eq!(spots[0], at);
        assert_eq!(spots.len(), 4);
        assert!(spots[1..].iter().all(|s| nav.room_at(*s) != nav.room_at(at)), "{spots:?}");
        let (a, b) = (share_of(&spots, 0, 2), share_of(&spots, 1, 2));
        assert_ne!(a[0], b[0], "two searchers start apart");
        assert_eq!(a.len() + b.len(), spots.len(), "between them they search every spot");
    }
}
