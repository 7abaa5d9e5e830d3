//! The broad phase: which objects' bounds overlap on this step, so that watched pairs far apart are
//! never queried (the paper's CollDet filters pairs before the sphere trees the same way).
//!
//! You need this module to see why a scene of hundreds of objects costs what its close pairs cost.
//! Sweep and prune along x over each object's world box: the boxes are kept sorted from step to step
//! (insertion sort, nearly linear when objects move a little per step), a sweep marks the pairs whose
//! boxes overlap in a bit matrix, and a watcher asks the matrix. Everything is allocated up front for
//! the world's object slots.

use crate::bounding_volume::Aabb;

/// Object boxes and the matrix of overlapping pairs of the latest [`update`](BroadPhase::update).
pub(crate) struct BroadPhase {
    /// Each slot's box on this step (`None`: empty slot).
    boxes: Vec<Option<Aabb>>,
    /// Slots with a box, by the boxes' lower x.
    order: Vec<u32>,
    /// Whether a slot is in `order`.
    listed: Vec<bool>,
    /// Bit `i * slots + j` (i < j): the boxes of slots i and j overlap.
    bits: Vec<u64>,
    /// Overlapping pairs found by the latest update.
    overlapping: u32,
}

impl BroadPhase {
    /// A broad phase for `slots` object slots.
    pub(crate) fn new(slots: usize) -> Self {
        Self {
            boxes: vec![None; slots],
            order: Vec::with_capacity(slots),
            listed: vec![false; slots],
            bits: vec![0; (slots * slots).div_ceil(64)],
            overlapping: 0,
        }
    }

    /// Sets slot `slot`'s box for this step (`None`: the slot is empty).
    pub(crate) fn set(&mut self, slot: usize, bounds: Option<Aabb>) {
        if let Some(b) = self.boxes.get_mut(slot) {
            *b = bounds;
        }
    }

    /// Sorts the boxes and finds every overlapping pair. Allocation-free.
    pub(crate) fn update(&mut self) {
        let Self { boxes, order, listed, bits, overlapping } = self;
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
        bits.fill(0);
        *overlapping = 0;
        let slots = boxes.len();
        for (i, &a) in order.iter().enumerate() {
            let Some(ba) = boxes[a as usize] else { continue };
            for &b in &order[i + 1..] {
                let Some(bb) = boxes[b as usize] else { continue };
                if bb.min.x > ba.max.x {
                    break;
                }
                let touch =
                    bb.min.y <= ba.max.y && ba.min.y <= bb.max.y && bb.min.z <= ba.max.z && ba.min.z <= bb.max.z;
                if touch {
                    let bit = (a.min(b) as usize) * slots + a.max(b) as usize;
                    bits[bit / 64] |= 1 << (bit % 64);
                    *overlapping += 1;
                }
            }
        }
    }

    /// Whether the boxes of slots `a` and `b` overlapped at the latest update.
    pub(crate) fn overlaps(&self, a: usize, b: usize) -> bool {
        let slots = self.boxes.len();
        if a == b || a >= slots || b >= slots {
            return false;
        }
        let bit = a.min(b) * slots + a.max(b);
        self.bits[bit / 64] & (1 << (bit % 64)) != 0
    }

    /// Overlapping pairs found by the latest update.
    pub(crate) fn overlapping(&self) -> u32 {
        self.overlapping
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube(at: Vec3, half: f32) -> Option<Aabb> {
        Some(Aabb::new(at - Vec3::splat(half), at + Vec3::splat(half)))
    }

    #[test]
    fn finds_exactly_the_pairs_whose_boxes_overlap_as_objects_move_come_and_go() {
        // 40 boxes on a jittered line and plane; compared with every pair tested directly, over steps
        // where they move, some leave and others come.
        let slots = 48;
        let mut broad = BroadPhase::new(slots);
        let mut seed = 7u32;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let mut boxes: Vec<Option<Aabb>> = vec![None; slots];
        for step in 0..30 {
            for (slot, b) in boxes.iter_mut().enumerate() {
                let present = (slot + step) % 7 != 0 && slot < 40 + step % 8;
                *b = if present {
                    let at = Vec3::new(slot as f32 * 0.3 + rand() * 0.5, rand(), rand() * 0.4);
                    cube(at, 0.1 + rand() * 0.2)
                } else {
                    None
                };
                broad.set(slot, *b);
            }
            broad.update();
            let mut expected = 0;
            for a in 0..slots {
                for b in a + 1..slots {
                    let want = match (boxes[a], boxes[b]) {
                        (Some(x), Some(y)) => x.min.cmple(y.max).all() && y.min.cmple(x.max).all(),
                        _ => false,
                    };
                    expected += want as u32;
                    assert_eq!(broad.overlaps(a, b), want, "step {step}: {a} and {b}");
                    assert_eq!(broad.overlaps(b, a), want);
                }
            }
            assert_eq!(broad.overlapping(), expected);
            assert!(expected > 0, "the scene has close pairs");
        }
        assert!(!broad.overlaps(3, 3) && !broad.overlaps(3, 1000), "an object with itself or out of range");
    }
}
