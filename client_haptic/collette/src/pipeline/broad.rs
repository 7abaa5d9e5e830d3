//! The broad phase: which objects' bounds overlap on this step, so that watched pairs far apart are
//! never queried (the paper's CollDet filters pairs before the sphere trees the same way).
//!
//! You need this module to see why a scene of hundreds of objects costs what its close pairs cost.
//! Sweep and prune along x: every step each object's world box is set, the objects are kept sorted by
//! their boxes' lower x (insertion sort, linear when objects move a little per step), and the objects
//! near one object are found by a binary search and a sweep over the few whose x range can meet its
//! box; a watched pair is one box test. Nothing is done for pairs nobody watches. Everything is
//! allocated up front for the world's object slots.

use crate::bounding_volume::Aabb;

/// Object boxes of the latest step, sorted along x.
pub(crate) struct BroadPhase {
    /// Each slot's box on this step (`None`: empty slot).
    boxes: Vec<Option<Aabb>>,
    /// Slots with a box, by the boxes' lower x.
    order: Vec<u32>,
    /// The boxes' lower x, in `order`'s order (for the binary search).
    lower_x: Vec<f32>,
    /// Whether a slot is in `order`.
    listed: Vec<bool>,
    /// The widest box along x.
    widest: f32,
}

impl BroadPhase {
    /// A broad phase for `slots` object slots.
    pub(crate) fn new(slots: usize) -> Self {
        Self {
            boxes: vec![None; slots],
            order: Vec::with_capacity(slots),
            lower_x: Vec::with_capacity(slots),
            listed: vec![false; slots],
            widest: 0.0,
        }
    }

    /// Sets slot `slot`'s box for this step (`None`: the slot is empty).
    pub(crate) fn set(&mut self, slot: usize, bounds: Option<Aabb>) {
        if let Some(b) = self.boxes.get_mut(slot) {
            *b = bounds;
        }
    }

    /// Sorts the boxes along x. Allocation-free.
    pub(crate) fn update(&mut self) {
        let Self { boxes, order, lower_x, listed, widest } = self;
        order.retain(|&s| {
            let keep = boxes[s as usize].is_some();
            listed[s as usize] = keep;
            keep
        });
        for (slot, b) in boxes.iter().enumerate() {
            if b.is_some() && !listed[slot] {
                listed[slot] = true;
                order.push(slot as u32); // within capacity: one entry per slot
            }
        }
        let min_x = |s: u32| boxes[s as usize].map_or(f32::INFINITY, |b| b.min.x);
        // Insertion sort: nearly sorted from the last step.
        for i in 1..order.len() {
            let mut j = i;
            while j > 0 && min_x(order[j - 1]) > min_x(order[j]) {
                order.swap(j - 1, j);
                j -= 1;
            }
        }
        lower_x.clear();
        lower_x.extend(order.iter().map(|&s| min_x(s))); // within capacity
        *widest = boxes.iter().flatten().map(|b| b.max.x - b.min.x).fold(0.0, f32::max);
    }

    /// Whether the boxes of slots `a` and `b` overlap on this step (false for a slot with itself).
    pub(crate) fn overlaps(&self, a: usize, b: usize) -> bool {
        match (a != b).then(|| (self.boxes.get(a), self.boxes.get(b))) {
            Some((Some(Some(x)), Some(Some(y)))) => touch(x, y),
            _ => false,
        }
    }

    /// Calls `visit` with every other slot whose box overlaps slot `a`'s: a binary search for the
    /// boxes that start less than the widest box's width before `a`'s, then a sweep until they start
    /// past its end.
    pub(crate) fn near(&self, a: usize, mut visit: impl FnMut(usize)) {
        let Some(Some(ba)) = self.boxes.get(a) else { return };
        let first = self.lower_x.partition_point(|&x| x < ba.min.x - self.widest);
        for (&slot, &x) in self.order[first..].iter().zip(&self.lower_x[first..]) {
            if x > ba.max.x {
                break;
            }
            let slot = slot as usize;
            if slot != a && self.boxes[slot].is_some_and(|b| touch(ba, &b)) {
                visit(slot);
            }
        }
    }
}

/// Whether two boxes overlap (touching counts).
fn touch(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cube(at: Vec3, half: f32) -> Option<Aabb> {
        Some(Aabb::new(at - Vec3::splat(half), at + Vec3::splat(half)))
    }

    #[test]
    fn finds_exactly_the_boxes_that_overlap_as_objects_move_come_and_go() {
        // 40 boxes of several sizes on a jittered line and plane; compared with every pair tested
        // directly, over steps where they move, some leave and others come.
        let slots = 48;
        let mut broad = BroadPhase::new(slots);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut roll = || rng.random::<f32>();
        let mut boxes: Vec<Option<Aabb>> = vec![None; slots];
        let mut found = 0;
        for step in 0..30 {
            for (slot, b) in boxes.iter_mut().enumerate() {
                let present = (slot + step) % 7 != 0 && slot < 40 + step % 8;
                *b = if present {
                    let at = Vec3::new(slot as f32 * 0.3 + roll() * 0.5, roll(), roll() * 0.4);
                    cube(at, 0.1 + roll() * roll() * 1.5)
                } else {
                    None
                };
                broad.set(slot, *b);
            }
            broad.update();
            for a in 0..slots {
                let mut near = Vec::new();
                broad.near(a, |b| near.push(b));
                near.sort_unstable();
                let want: Vec<usize> = (0..slots)
                    .filter(|&b| match (boxes[a], boxes[b]) {
                        (Some(x), Some(y)) => a != b && x.min.cmple(y.max).all() && y.min.cmple(x.max).all(),
                        _ => false,
                    })
                    .collect();
                assert_eq!(near, want, "step {step}: the boxes near {a}");
                for b in 0..slots {
                    assert_eq!(broad.overlaps(a, b), want.contains(&b), "step {step}: {a} and {b}");
                }
                found += want.len();
            }
        }
        assert!(found > 100, "the scene has close pairs: {found}");
        assert!(!broad.overlaps(3, 3) && !broad.overlaps(3, 1000), "an object with itself or out of range");
    }
}
