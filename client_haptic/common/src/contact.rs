//! Contacts reported by collision detection (the OnCollision event's payload).

use glam::Vec3;

/// Capacity of a [`ContactSet`]; the collision layer stops adding pairs (and flags the set as truncated)
/// once it is full, so the set never allocates.
pub const MAX_CONTACTS: usize = 4096;

/// One overlapping pair of inner spheres (or, for a point probe, one penetration), in world coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Contact {
    /// Centre of the collision (centroid of the lens), metres.
    pub point: Vec3,
    /// Unit normal pointing from object B towards object A: the direction in which A is pushed out.
    pub normal: Vec3,
    /// Overlap volume of the pair, cubic metres (0 for point-probe contacts).
    pub volume: f32,
    /// Penetration depth along `normal`, metres.
    pub depth: f32,
}

/// The latest contacts between two watched objects A (usually the tool) and B (the touched object).
///
/// A fixed-capacity, `Copy`-free but allocation-free value: it lives inside lock-free buffers that are
/// allocated once up front.
#[derive(Clone, Debug)]
pub struct ContactSet {
    /// Identifier of object A (the tool), as given by the collision layer.
    pub object_a: u32,
    /// Identifier of object B (the touched object).
    pub object_b: u32,
    /// Monotonic sequence number of the collision step that produced this set.
    pub sequence: u64,
    /// Time at which the poses used for this set were sampled, in microseconds on the haptic clock.
    pub timestamp_us: u64,
    /// Total overlap volume, cubic metres; includes `estimated_volume`.
    pub total_volume: f32,
    /// Part of `total_volume` that was estimated (not traversed) by a time-budgeted query, cubic metres.
    pub estimated_volume: f32,
    /// True when more pairs overlapped than fit, or the query stopped early on its budget.
    pub truncated: bool,
    len: usize,
    contacts: Box<[Contact; MAX_CONTACTS]>,
}

impl Default for ContactSet {
    fn default() -> Self {
        Self::new()
    }
}

impl ContactSet {
    /// An empty set with its full capacity allocated (call this once, off the hot path).
    pub fn new() -> Self {
        let contacts: Box<[Contact; MAX_CONTACTS]> = vec![Contact::default(); MAX_CONTACTS]
            .into_boxed_slice()
            .try_into()
            .unwrap_or_else(|_| unreachable!("vector has exactly MAX_CONTACTS elements"));
        Self {
            object_a: 0,
            object_b: 0,
            sequence: 0,
            timestamp_us: 0,
            total_volume: 0.0,
            estimated_volume: 0.0,
            truncated: false,
            len: 0,
            contacts,
        }
    }

    /// Forgets all contacts (keeps the capacity).
    pub fn clear(&mut self) {
        self.len = 0;
        self.total_volume = 0.0;
        self.estimated_volume = 0.0;
        self.truncated = false;
    }

    /// Adds a contact; returns false (and marks the set truncated) when full.
    #[inline]
    pub fn push(&mut self, contact: Contact) -> bool {
        if self.len == MAX_CONTACTS {
            self.truncated = true;
            return false;
        }
        self.contacts[self.len] = contact;
        self.len += 1;
        true
    }

    /// The contacts held.
    #[inline]
    pub fn as_slice(&self) -> &[Contact] {
        &self.contacts[..self.len]
    }

    /// The contacts held, to change in place (e.g. to scale their volumes).
    #[inline]
    pub fn as_mut_slice(&mut self) -> &mut [Contact] {
        &mut self.contacts[..self.len]
    }

    /// Number of contacts held.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no contact is held.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Copies `other` into `self` without allocating.
    pub fn copy_from(&mut self, other: &ContactSet) {
        self.object_a = other.object_a;
        self.object_b = other.object_b;
        self.sequence = other.sequence;
        self.timestamp_us = other.timestamp_us;
        self.total_volume = other.total_volume;
        self.estimated_volume = other.estimated_volume;
        self.truncated = other.truncated;
        self.len = other.len;
        self.contacts[..other.len].copy_from_slice(&other.contacts[..other.len]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_set_refuses_more_and_says_it_was_truncated() {
        let mut set = ContactSet::new();
        for _ in 0..MAX_CONTACTS {
            assert!(set.push(Contact::default()));
        }
        assert!(!set.push(Contact::default()));
        assert!(set.truncated);
        assert_eq!(set.len(), MAX_CONTACTS);
        set.clear();
        assert!(set.is_empty() && !set.truncated);
    }

    #[test]
    fn copy_from_reproduces_the_contacts() {
        let mut a = ContactSet::new();
        a.push(Contact { point: Vec3::X, normal: Vec3::Y, volume: 2.0, depth: 0.5 });
        a.total_volume = 2.0;
        a.sequence = 7;
        let mut b = ContactSet::new();
        b.copy_from(&a);
        assert_eq!(b.as_slice(), a.as_slice());
        assert_eq!(b.sequence, 7);
    }
}
