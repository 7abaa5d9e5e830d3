//! What a watcher of one object against the whole scene publishes, and the summary a watcher between
//! two objects can publish instead of their contacts.
//!
//! You need this module to watch a tool against hundreds of objects with one buffer: a scene watcher
//! queries its object against every object whose bounds touch it (the broad phase's candidates) and
//! publishes all their contacts in one [`SceneContacts`], grouped by object, or all their spheres near
//! its origin in one [`NearSpheres`](super::NearSpheres) (each sphere names its object). Fixed
//! capacity, allocated once, like every published result.

use haptic_common::{Contact, ContactSet};

/// Most objects a [`SceneContacts`] lists per step (more are counted in `overflow`, their contacts not kept).
pub const MAX_TOUCHED: usize = 64;

/// One object's share of a [`SceneContacts`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Touched {
    /// The object (its slot, as in [`ObjectId`](super::ObjectId)).
    pub object: u32,
    /// Its contacts' place in [`SceneContacts::contacts`].
    start: u32,
    len: u32,
    /// Its overlap volume with the watcher's object, including what was estimated.
    pub total_volume: f32,
    /// Part of `total_volume` a budgeted query estimated.
    pub estimated_volume: f32,
    /// True when its query stopped on the budget or the contacts did not all fit.
    pub truncated: bool,
}

/// The contacts of one object against every object it overlaps, grouped by object.
#[derive(Clone, Debug)]
pub struct SceneContacts {
    contacts: ContactSet,
    touched: Box<[Touched; MAX_TOUCHED]>,
    count: usize,
    /// Objects overlapped but not listed (the list was full).
    pub overflow: u32,
    /// The watcher's object.
    pub object: u32,
    /// Step that produced the set (0: none yet).
    pub sequence: u64,
    /// Timestamp of the watcher's object's pose (the oldest of the poses used), µs.
    pub timestamp_us: u64,
}

impl Default for SceneContacts {
    fn default() -> Self {
        Self {
            contacts: ContactSet::new(),
            touched: Box::new([Touched::default(); MAX_TOUCHED]),
            count: 0,
            overflow: 0,
            object: 0,
            sequence: 0,
            timestamp_us: 0,
        }
    }
}

impl SceneContacts {
    /// Empties the set (keeps its memory).
    pub fn clear(&mut self) {
        self.contacts.clear();
        self.count = 0;
        self.overflow = 0;
    }

    /// Adds object `object`'s contacts (a pair query's result); an object without contacts or volume
    /// is not listed. Returns false when the list was full.
    pub fn add(&mut self, object: u32, set: &ContactSet) -> bool {
        if set.is_empty() && set.total_volume <= 0.0 {
            return true;
        }
        if self.count == MAX_TOUCHED {
            self.overflow += 1;
            return false;
        }
        let start = self.contacts.len();
        let mut truncated = set.truncated;
        for c in set.as_slice() {
            truncated |= !self.contacts.push(*c);
        }
        self.touched[self.count] = Touched {
            object,
            start: start as u32,
            len: (self.contacts.len() - start) as u32,
            total_volume: set.total_volume,
            estimated_volume: set.estimated_volume,
            truncated,
        };
        self.count += 1;
        true
    }

    /// The objects touched, in the order they were added.
    pub fn touched(&self) -> &[Touched] {
        &self.touched[..self.count]
    }

    /// The contacts of one listed object.
    pub fn contacts_of(&self, touched: &Touched) -> &[Contact] {
        let slice = self.contacts.as_slice();
        let start = (touched.start as usize).min(slice.len());
        &slice[start..(start + touched.len as usize).min(slice.len())]
    }

    /// Every contact of every listed object.
    pub fn contacts(&self) -> &[Contact] {
        self.contacts.as_slice()
    }

    /// Summed overlap volume of the listed objects.
    pub fn total_volume(&self) -> f32 {
        self.touched().iter().map(|t| t.total_volume).sum()
    }
}

/// What a watcher between two objects publishes when only whether and how much they overlap matters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairSummary {
    /// Object A.
    pub object_a: u32,
    /// Object B.
    pub object_b: u32,
    /// Overlapping sphere pairs found.
    pub pairs: u32,
    /// Overlap volume, including what was estimated.
    pub total_volume: f32,
    /// Step that measured it (0: none yet).
    pub sequence: u64,
    /// Timestamp of the older of the two poses used, µs.
    pub timestamp_us: u64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn set_of(n: usize, volume: f32) -> ContactSet {
        let mut set = ContactSet::new();
        for i in 0..n {
            set.push(Contact { point: Vec3::X * i as f32, normal: Vec3::Y, volume, depth: 0.1 });
        }
        set.total_volume = n as f32 * volume;
        set
    }

    #[test]
    fn objects_are_listed_with_their_own_contacts_and_the_list_stays_within_its_capacity() {
        let mut scene = SceneContacts::default();
        assert!(scene.add(3, &set_of(2, 1.0)));
        assert!(scene.add(4, &ContactSet::new()), "nothing to list");
        assert!(scene.add(9, &set_of(5, 0.5)));
        let touched = scene.touched();
        assert_eq!(touched.iter().map(|t| t.object).collect::<Vec<_>>(), vec![3, 9]);
        assert_eq!(scene.contacts_of(&touched[1]).len(), 5);
        assert_eq!(scene.contacts_of(&touched[1])[4].point, Vec3::X * 4.0);
        assert_eq!(scene.total_volume(), 4.5);
        for i in 0..MAX_TOUCHED {
            scene.add(100 + i as u32, &set_of(1, 1.0));
        }
        assert_eq!((scene.touched().len(), scene.overflow), (MAX_TOUCHED, 2));
        scene.clear();
        assert!(scene.touched().is_empty() && scene.contacts().is_empty() && scene.overflow == 0);
    }

    #[test]
    fn contacts_past_the_set_capacity_mark_their_object_truncated() {
        let mut scene = SceneContacts::default();
        let big = set_of(haptic_common::MAX_CONTACTS - 1, 1.0);
        assert!(scene.add(1, &big) && scene.add(2, &set_of(3, 1.0)));
        let touched = scene.touched();
        assert!(!touched[0].truncated && touched[1].truncated);
        assert_eq!(scene.contacts_of(&touched[1]).len(), 1, "one of three fitted");
    }
}
