//! The simultaneous descent of two trees shared by the exact and budgeted overlap queries.

use super::{Budget, OverlapResult};
use crate::partitioning::{InnerSphereTree, Node};
use crate::query::QueryWorkspace;
use crate::shape::{Lens, lens, sphere_volume};
use glam::{Affine3A, Vec3};
use haptic_common::Pose;
use std::time::Instant;

/// How many node pairs are tested between two clock reads.
const CLOCK_STRIDE: u32 = 8;

pub(super) struct Engine<'a, S> {
    a: &'a InnerSphereTree,
    b: &'a InnerSphereTree,
    pos12: Affine3A,
    budget: Budget,
    aggregate: bool,
    sink: S,
    until_clock: u32,
    exhausted: bool,
    pub(super) result: OverlapResult,
}

impl<'a, S: FnMut(&Lens, Vec3, Vec3)> Engine<'a, S> {
    /// `aggregate`: a node lying wholly inside one leaf sphere of the other tree contributes its summed
    /// volume as one contact (exact volume, far fewer pairs) instead of one contact per leaf pair.
    /// Every volume is weighted by both spheres' weights ([`InnerSphereTree::weights`]).
    pub(super) fn new(
        a: &'a InnerSphereTree,
        b: &'a InnerSphereTree,
        pos12: Pose,
        budget: Budget,
        aggregate: bool,
        sink: S,
    ) -> Self {
        let result = OverlapResult { complete: true, ..OverlapResult::default() };
        Self {
            a,
            b,
            pos12: Affine3A::from_rotation_translation(pos12.rotation, pos12.translation),
            budget,
            aggregate,
            sink,
            until_clock: 0,
            exhausted: false,
            result,
        }
    }

    /// Maps a point of B's frame into A's frame.
    #[inline(always)]
    fn tp(&self, p: Vec3) -> Vec3 {
        Vec3::from(self.pos12.transform_point3a(p.into()))
    }

    /// Exact depth-first descent.
    pub(super) fn run_depth_first(&mut self, ws: &mut QueryWorkspace) {
        ws.stack.clear();
        ws.stack.push((0, 0));
        self.drain_stack(ws);
    }

    /// Breadth-first descent in a fixed ring; overflow is refined depth-first; stops on the budget.
    pub(super) fn run_breadth_first(&mut self, ws: &mut QueryWorkspace) {
        let cap = ws.ring.len();
        let (mut head, mut len) = (0usize, 1usize);
        ws.ring[0] = (0, 0);
        ws.stack.clear();
        while len > 0 {
            if self.out_of_budget(len as f32 * ws.estimate_ns) {
                break;
            }
            let (ia, ib) = ws.ring[head];
            head = (head + 1) % cap;
            len -= 1;
            let (children, n) = self.visit(ia, ib);
            for &pair in &children[..n] {
                if len < cap {
                    ws.ring[(head + len) % cap] = pair;
                    len += 1;
                } else {
                    ws.stack.push(pair);
                }
            }
            if !ws.stack.is_empty() {
                self.drain_stack(ws);
            }
        }
        if len > 0 {
            let start = Instant::now();
            for k in 0..len {
                let (ia, ib) = ws.ring[(head + k) % cap];
                self.estimate(ia, ib);
            }
            if len >= 32 {
                // Keep the reserve calibrated to this machine (slow to shrink, quick to grow).
                let per = start.elapsed().as_nanos() as f32 / len as f32;
                ws.estimate_ns =
                    if per > ws.estimate_ns { per } else { 0.9 * ws.estimate_ns + 0.1 * per }.clamp(5.0, 1000.0);
            }
        }
    }

    fn drain_stack(&mut self, ws: &mut QueryWorkspace) {
        while let Some((ia, ib)) = ws.stack.pop() {
            if self.out_of_budget(0.0) {
                self.estimate(ia, ib);
                while let Some((ia, ib)) = ws.stack.pop() {
                    self.estimate(ia, ib);
                }
                return;
            }
            let (children, n) = self.visit(ia, ib);
            ws.stack.extend_from_slice(&children[..n]);
        }
    }

    /// True once the budget is spent; `reserve_ns` is kept back for estimating what is still queued.
    fn out_of_budget(&mut self, reserve_ns: f32) -> bool {
        if self.exhausted {
            return true;
        }
        self.exhausted = match self.budget {
            Budget::Unlimited => false,
            Budget::NodePairs(max) => self.result.node_pairs >= max,
            Budget::Deadline(deadline) => {
                if self.until_clock == 0 {
                    self.until_clock = CLOCK_STRIDE;
                    Instant::now() + std::time::Duration::from_nanos(reserve_ns as u64) >= deadline
                } else {
                    self.until_clock -= 1;
                    false
                }
            }
        };
        if self.exhausted {
            self.result.complete = false;
        }
        self.exhausted
    }

    /// Tests a node pair; refines leaf pairs exactly; returns the child pairs to visit.
    #[inline]
    fn visit(&mut self, ia: u32, ib: u32) -> ([(u32, u32); 4], usize) {
        let mut children = [(0u32, 0u32); 4];
        self.result.node_pairs += 1;
        let na = &self.a.nodes[ia as usize];
        let nb = &self.b.nodes[ib as usize];
        let cb = self.tp(nb.bound.center);
        let r = na.bound.radius + nb.bound.radius;
        if na.bound.center.distance_squared(cb) >= r * r {
            return (children, 0);
        }
        if na.leaf && nb.leaf {
            self.leaf_pairs(na, nb);
            return (children, 0);
        }
        if self.aggregate && self.contained(na, nb, cb) {
            return (children, 0);
        }
        // Children are tested here, so pairs that cannot overlap are never queued.
        let descend_a = nb.leaf || (!na.leaf && na.bound.radius >= nb.bound.radius);
        let mut n = 0;
        if descend_a {
            for c in na.range() {
                let child = &self.a.nodes[c].bound;
                let r = child.radius + nb.bound.radius;
                if child.center.distance_squared(cb) < r * r {
                    children[n] = (c as u32, ib);
                    n += 1;
                }
            }
        } else {
            for c in nb.range() {
                let child = &self.b.nodes[c].bound;
                let r = na.bound.radius + child.radius;
                if na.bound.center.distance_squared(self.tp(child.center)) < r * r {
                    children[n] = (ia, c as u32);
                    n += 1;
                }
            }
        }
        (children, n)
    }

    #[inline]
    fn leaf_pairs(&mut self, na: &Node, nb: &Node) {
        for ib in nb.range() {
            let (sb, wb) = (&self.b.spheres[ib], self.b.weights[ib]);
            let cb = self.tp(sb.center);
            for ia in na.range() {
                let (sa, wa) = (&self.a.spheres[ia], self.a.weights[ia]);
                if let Some(mut l) = lens(sa.center, sa.radius, cb, sb.radius)
                    && l.volume > 0.0
                {
                    l.volume *= wa * wb;
                    self.result.total_volume += l.volume;
                    self.result.leaf_pairs += 1;
                    (self.sink)(&l, sa.center, cb);
                }
            }
        }
    }

    /// If one node lies wholly inside a single leaf sphere of the other tree, adds the node's volume
    /// (its mesh share times the sphere's weight).
    ///
    /// Exact: spheres of one tree are disjoint, so spheres inside one of them overlap no other.
    #[inline]
    fn contained(&mut self, na: &Node, nb: &Node, cb: Vec3) -> bool {
        if nb.leaf {
            for ib in nb.range() {
                let sb = &self.b.spheres[ib];
                let c = self.tp(sb.center);
                let d = na.bound.center.distance(c);
                if d + na.bound.radius <= sb.radius {
                    let volume = na.mesh_share * self.b.weights[ib];
                    let l = Lens { volume, centroid: na.bound.center, depth: sb.radius + na.bound.radius - d };
                    self.emit_aggregate(&l, na.bound.center, c);
                    return true;
                }
            }
        } else if na.leaf {
            for ia in na.range() {
                let sa = &self.a.spheres[ia];
                let d = sa.center.distance(cb);
                if d + nb.bound.radius <= sa.radius {
                    let volume = nb.mesh_share * self.a.weights[ia];
                    let l = Lens { volume, centroid: cb, depth: sa.radius + nb.bound.radius - d };
                    self.emit_aggregate(&l, sa.center, cb);
                    return true;
                }
            }
        }
        false
    }

    fn emit_aggregate(&mut self, l: &Lens, ca: Vec3, cb: Vec3) {
        if l.volume > 0.0 {
            self.result.total_volume += l.volume;
            self.result.aggregated_pairs += 1;
            (self.sink)(l, ca, cb);
        }
    }

    /// Estimates a node pair from its bounds' lens scaled by both fill ratios and mean weights.
    fn estimate(&mut self, ia: u32, ib: u32) {
        let na = &self.a.nodes[ia as usize];
        let nb = &self.b.nodes[ib as usize];
        let cb = self.tp(nb.bound.center);
        let Some(mut l) = lens(na.bound.center, na.bound.radius, cb, nb.bound.radius) else { return };
        let fill = |n: &Node| (n.volume / sphere_volume(n.bound.radius).max(f32::MIN_POSITIVE)).min(1.0);
        let weight = |n: &Node| if n.volume > 0.0 { n.mesh_share / n.volume } else { 1.0 };
        l.volume = (l.volume * fill(na) * fill(nb) * weight(na) * weight(nb)).min(na.mesh_share).min(nb.mesh_share);
        if l.volume <= 0.0 {
            return;
        }
        self.result.total_volume += l.volume;
        self.result.estimated_volume += l.volume;
        self.result.estimated_pairs += 1;
        (self.sink)(&l, na.bound.center, cb);
    }
}
