//! A level's rules checked: every reference, every geometric rule, every room reachable; an error
//! names the place and what is wrong.

use glam::Vec2;

use super::{Level, MIN_GUARDS, MIN_ROOMS, MIN_TARGETS, NavGraph};

impl Level {
    pub(super) fn validate(&self) -> Result<(), (String, String)> {
        let err = |place: String, problem: String| Err((place, problem));
        if !(self.time_limit_s.is_finite() && self.time_limit_s > 0.0) {
            return err("time_limit_s".into(), format!("must be a positive number, got {}", self.time_limit_s));
        }
        for d in crate::rules::Difficulty::ALL {
            if let Some(why) = self.tuning(d).out_of_range() {
                return err(format!("difficulties.{}", d.name()), why);
            }
        }
        if self.rooms.len() < MIN_ROOMS {
            return err(
                "rooms".into(),
                format!("a museum needs at least {MIN_ROOMS} rooms, found {}", self.rooms.len()),
            );
        }
        for (i, room) in self.rooms.iter().enumerate() {
            let place = format!("rooms[{i}] ({})", room.id);
            if !(room.min.is_finite() && room.max.is_finite()) {
                return err(place, "corners must be finite numbers".into());
            }
            if room.max.x - room.min.x < 2.0 || room.max.y - room.min.y < 2.0 {
                return err(
                    place,
                    format!("must be at least 2 m on each side (min {:?}, max {:?})", room.min, room.max),
                );
            }
            if self.rooms[..i].iter().any(|r| r.id == room.id) {
                return err(place, format!("duplicate room id `{}`", room.id));
            }
            for (j, other) in self.rooms[..i].iter().enumerate() {
                let overlap = room.min.x < other.max.x - 1e-3
                    && other.min.x < room.max.x - 1e-3
                    && room.min.y < other.max.y - 1e-3
                    && other.min.y < room.max.y - 1e-3;
                if overlap {
                    return err(place, format!("overlaps rooms[{j}] ({})", other.id));
                }
            }
        }
        for (i, door) in self.doors.iter().enumerate() {
            let place = format!("doors[{i}]");
            let (a, b) = (&door.between.0, &door.between.1);
            let (Some(ra), Some(rb)) = (self.room_index(a), self.room_index(b)) else {
                let missing = if self.room_index(a).is_none() { a } else { b };
                return err(place, format!("names an unknown room `{missing}`"));
            };
            if ra == rb {
                return err(place, format!("joins room `{a}` to itself"));
            }
            if !(door.width.is_finite() && door.width >= 0.8 && door.width <= 4.0) {
                return err(place, format!("width must be between 0.8 and 4 m, got {}", door.width));
            }
            if !(0.0..=1.0).contains(&door.attenuation) {
                return err(place, format!("attenuation must be within 0..=1, got {}", door.attenuation));
            }
            if self.rooms[ra].shared_wall_axis(&self.rooms[rb], door.at).is_none() {
                return err(place, format!("{:?} is not on a wall shared by `{a}` and `{b}`", door.at));
            }
        }
        let nav = NavGraph::new(self);
        if let Some(unreached) = nav.unreachable_room(0) {
            return err(
                format!("rooms[{unreached}] ({})", self.rooms[unreached].id),
                "cannot be reached from the first room through doors".into(),
            );
        }
        let inside = |p: Vec2| self.room_at(p).is_some();
        for (i, case) in self.cases.iter().enumerate() {
            if !inside(case.at) {
                return err(format!("cases[{i}] ({})", case.id), format!("{:?} is outside every room", case.at));
            }
            if self.cases[..i].iter().any(|c| c.id == case.id) {
                return err(format!("cases[{i}]"), format!("duplicate case id `{}`", case.id));
            }
        }
        if self.targets.len() < MIN_TARGETS {
            return err(
                "targets".into(),
                format!("a heist needs at least {MIN_TARGETS} targets, found {}", self.targets.len()),
            );
        }
        for (i, t) in self.targets.iter().enumerate() {
            if t.copies < 3 {
                return err(
                    format!("targets[{i}]"),
                    format!("needs at least 3 copies (1 real + 2 fakes), got {}", t.copies),
                );
            }
            if self.targets[..i].iter().any(|o| o.kind == t.kind) {
                return err(format!("targets[{i}]"), format!("artifact {:?} is listed twice", t.kind));
            }
        }
        if self.copy_count() > self.cases.len() {
            return err(
                "cases".into(),
                format!("{} copies need as many display cases, found {}", self.copy_count(), self.cases.len()),
            );
        }
        if self.guards.len() < MIN_GUARDS {
            return err(
                "guards".into(),
                format!("a museum needs at least {MIN_GUARDS} guards, found {}", self.guards.len()),
            );
        }
        for (g, guard) in self.guards.iter().enumerate() {
            if guard.route.is_empty() {
                return err(format!("guards[{g}] ({})", guard.name), "route is empty".into());
            }
            for (w, p) in guard.route.iter().enumerate() {
                if !inside(*p) {
                    return err(format!("guards[{g}].route[{w}]"), format!("{p:?} is outside every room"));
                }
            }
        }
        for (i, p) in self.props.iter().enumerate() {
            if !inside(*p) {
                return err(format!("props[{i}]"), format!("{p:?} is outside every room"));
            }
        }
        for (name, p) in [("workbench", self.workbench), ("vive_spawn", self.vive_spawn), ("exit", self.exit)] {
            if !inside(p) {
                return err(name.into(), format!("{p:?} is outside every room"));
            }
        }
        Ok(())
    }
}
