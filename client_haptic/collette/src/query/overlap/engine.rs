//! The simultaneous descent of two trees shared by the exact and budgeted overlap queries.

use super::affine::WideAffine;
use super::batch::{Lanes, PAIR_BATCH, PairBatch};
use super::result::{Budget, OverlapResult};
use super::sink::Sink;
use crate::partitioning::{InnerSphereTree, Node};
use crate::query::QueryWorkspace;
use crate::shape::{Lens, lens, lens_x4, sphere_volume};
use glam::{Affine3A, Vec3, Vec4};
use haptic_common::Pose;
use std::time::Instant;

/// How many node pairs are tested between two clock reads.
const CLOCK_STRIDE: u32 = 8;

/// Room on [`Engine::subtree_in_sphere`]'s stack: a valid tree is at most 64 levels deep and leaves at
/// most three siblings per level waiting, so it never overflows (and spills onto the pair stack if it did).
const LOCAL_DEPTH: usize = 200;

/// Four children (centres and radii, in A's frame; `leaves` has the bits of those that are leaves)
/// against one node's bound (`c`, `r`; `leaf` when it is a leaf): the squared distances, the lanes that
/// overlap it, and the lanes that containment may settle (one bound inside the other, the outer one a
/// leaf's, as a node inside a leaf sphere needs).
///
/// With a `margin` (a neighbour list's skin, [`super::coherent`]) a lane hits when the bounds come
/// within `margin` of each other and nests only when it stays nested after either moves by `margin`;
/// the exact queries pass a literal 0, which compiles to the test without it.
#[inline(always)]
fn four_against(
    centres: [Vec4; 3],
    radii: Vec4,
    leaves: u32,
    c: Vec3,
    r: f32,
    leaf: bool,
    margin: f32,
) -> (Vec4, u32, u32) {
    let (dx, dy, dz) = (centres[0] - Vec4::splat(c.x), centres[1] - Vec4::splat(c.y), centres[2] - Vec4::splat(c.z));
    let d2 = dx * dx + dy * dy + dz * dz;
    let (reach, gap) = (radii + Vec4::splat(r), radii - Vec4::splat(r));
    if margin != 0.0 {
        let reach = reach + Vec4::splat(margin);
        let hits = d2.cmplt(reach * reach).bitmask();
        // Child inside a leaf `c`: |d| + radius + margin <= r; leaf child around `c`: |d| + r + margin <= radius.
        let (inner, outer) = (gap + Vec4::splat(margin), gap - Vec4::splat(margin));
        let in_leaf = if leaf { d2.cmple(inner * inner).bitmask() & inner.cmple(Vec4::ZERO).bitmask() } else { 0 };
        let around = leaves & d2.cmple(outer * outer).bitmask() & outer.cmpge(Vec4::ZERO).bitmask();
        return (d2, hits, in_leaf | around);
    }
    let hits = d2.cmplt(reach * reach).bitmask();
    let outer_is_leaf =
        if leaf { gap.cmple(Vec4::ZERO).bitmask() } else { 0 } | (leaves & gap.cmpge(Vec4::ZERO).bitmask());
    (d2, hits, d2.cmple(gap * gap).bitmask() & outer_is_leaf)
}

pub(super) struct Engine<'a, S> {
    a: &'a InnerSphereTree,
    b: &'a InnerSphereTree,
    pub(super) pos12: Affine3A,
    /// `pos12`'s entries, each in all four lanes (moving four of B's centres at once).
    pub(super) wide: WideAffine,
    budget: Budget,
    aggregate: bool,
    pub(super) sink: S,
    pairs: PairBatch,
    /// Stack of A's blocks for [`Engine::subtree_in_sphere`].
    local: [u32; LOCAL_DEPTH],
    until_clock: u32,
    exhausted: bool,
    pub(super) result: OverlapResult,
}

impl<'a, S: Sink> Engine<'a, S> {
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
        let pos12 = Affine3A::from_rotation_translation(pos12.rotation, pos12.translation);
        Self {
            a,
            b,
            pos12,
            wide: WideAffine::new(&pos12),
            budget,
            aggregate,
            sink,
            pairs: PairBatch::new(),
            local: [0; LOCAL_DEPTH],
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

    /// The skin a neighbour list is collected with; a literal 0 for every other query.
    #[inline(always)]
    fn margin(&self) -> f32 {
        if S::COLLECTS { self.sink.margin() } else { 0.0 }
    }

    /// Exact depth-first descent.
    pub(super) fn run_depth_first(&mut self, ws: &mut QueryWorkspace) {
        ws.stack.clear();
        if self.root_needs_visit() {
            ws.stack.push((0, 0));
        }
        self.drain_stack(ws);
        self.flush_pairs();
    }

    /// Breadth-first descent in a fixed ring; overflow is refined depth-first; stops on the budget.
    pub(super) fn run_breadth_first(&mut self, ws: &mut QueryWorkspace) {
        ws.stack.clear();
        if self.root_needs_visit() {
            self.breadth_first(ws);
        }
        self.flush_pairs();
    }

    fn breadth_first(&mut self, ws: &mut QueryWorkspace) {
        let cap = ws.ring.len();
        let (mut head, mut len) = (0usize, 1usize);
        ws.ring[0] = (0, 0);
        while len > 0 {
            if self.out_of_budget(len as f32 * ws.estimate_ns) {
                break;
            }
            let (ia, ib) = ws.ring[head];
            head = (head + 1) % cap;
            len -= 1;
            // The stack is empty here: the children land on it, then move to the ring while it has room.
            self.visit(ia, ib, &mut ws.stack);
            let mut moved = 0;
            while moved < ws.stack.len() && len < cap {
                ws.ring[(head + len) % cap] = ws.stack[moved];
                len += 1;
                moved += 1;
            }
            ws.stack.drain(..moved);
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

    /// Tests the two roots; handles them when the answer ends there (two leaves, one inside a leaf
    /// sphere); true when their children must be visited.
    fn root_needs_visit(&mut self) -> bool {
        let (na, nb) = (self.a.nodes[0], self.b.nodes[0]);
        let cb = self.tp(nb.bound.center);
        let r = na.bound.radius + nb.bound.radius + self.margin();
        if na.bound.center.distance_squared(cb) >= r * r {
            return false;
        }
        if na.leaf && nb.leaf {
            self.leaf_pairs(&na, &nb);
            return false;
        }
        !(self.aggregate && self.contained(&na, &nb, cb))
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
            self.visit(ia, ib, &mut ws.stack);
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

    /// Visits an overlapping node pair that does not end the descent: tests the larger node's children
    /// (four at once, from its [`crate::partitioning::ChildBlock`]) against the other node, settles the
    /// child pairs that end here (two leaves: their sphere pairs; with `aggregate`, a node inside one
    /// leaf sphere: one contact) and pushes the others, which overlap and must be visited in turn, on
    /// `next`. A subtree of A against one sphere of B (most of an exact query's work) goes to
    /// [`Engine::subtree_in_sphere`].
    #[inline]
    fn visit(&mut self, ia: u32, ib: u32, next: &mut Vec<(u32, u32)>) {
        self.result.node_pairs += 1;
        let (a, b) = (self.a, self.b);
        let na = &a.nodes[ia as usize];
        let nb = &b.nodes[ib as usize];
        if nb.leaf && nb.count == 1 && !na.leaf && self.budget == Budget::Unlimited {
            // The common case deep in the descent: a subtree of A against one sphere of B.
            let s = &b.spheres[nb.first as usize];
            self.subtree_in_sphere(ia, self.tp(s.center), s.radius, nb.first, ib, next);
        } else if nb.leaf || (!na.leaf && na.bound.radius >= nb.bound.radius) {
            // A's children against B (in A's frame).
            let (cb, rb) = Self::bound_of(b, nb);
            let cb = self.tp(cb);
            let blk = a.block(ia);
            let (_, mut hits, nested) =
                four_against([blk.x, blk.y, blk.z], blk.r, blk.leaf, cb, rb, nb.leaf, self.margin());
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let child = blk.node[lane];
                if nb.leaf && blk.leaf >> lane & 1 != 0 {
                    if blk.single >> lane & 1 != 0 && nb.count == 1 {
                        let ca = Vec3::new(blk.x[lane], blk.y[lane], blk.z[lane]);
                        self.sphere_pair(ca, blk.r[lane], blk.link[lane], cb, rb, nb.first);
                    } else {
                        self.leaf_pairs(&a.nodes[child as usize], nb);
                    }
                } else if !(self.aggregate
                    && nested >> lane & 1 != 0
                    && self.contained(&a.nodes[child as usize], nb, self.tp(nb.bound.center)))
                {
                    next.push((child, ib));
                }
            }
        } else {
            // B's children, moved into A's frame four at once, against A.
            let (ca, ra) = Self::bound_of(a, na);
            let blk = b.block(ib);
            let [x, y, z] = self.wide.point(blk.x, blk.y, blk.z);
            let (_, mut hits, nested) = four_against([x, y, z], blk.r, blk.leaf, ca, ra, na.leaf, self.margin());
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let child = blk.node[lane];
                if na.leaf && blk.leaf >> lane & 1 != 0 {
                    if blk.single >> lane & 1 != 0 && na.count == 1 {
                        let cb = Vec3::new(x[lane], y[lane], z[lane]);
                        self.sphere_pair(ca, ra, na.first, cb, blk.r[lane], blk.link[lane]);
                    } else {
                        self.leaf_pairs(na, &b.nodes[child as usize]);
                    }
                } else if !(self.aggregate && nested >> lane & 1 != 0 && {
                    let nc = &b.nodes[child as usize];
                    self.contained(na, nc, self.tp(nc.bound.center))
                }) {
                    next.push((ia, child));
                }
            }
        }
    }

    /// Descends A's subtree under inner node `ia` against B's sphere `sb` (centre `cb` in A's frame,
    /// radius `rb`, in leaf `ib`) on a small local stack: the same answer as visiting each pair, without
    /// reloading B's side or transforming it again. Exact queries only (no budget is checked).
    fn subtree_in_sphere(&mut self, ia: u32, cb: Vec3, rb: f32, sb: u32, ib: u32, next: &mut Vec<(u32, u32)>) {
        let a = self.a;
        let wb = self.b.weights[sb as usize];
        let mut len = 1;
        self.local[0] = a.block_of[ia as usize];
        while len > 0 {
            len -= 1;
            self.result.node_pairs += 1;
            let blk = a.block_at(self.local[len]);
            let (d2, hits, nested) = four_against([blk.x, blk.y, blk.z], blk.r, blk.leaf, cb, rb, true, self.margin());
            let leaves = hits & blk.leaf;
            for lane in Lanes(leaves & blk.single) {
                let ca = Vec3::new(blk.x[lane], blk.y[lane], blk.z[lane]);
                self.sphere_pair(ca, blk.r[lane], blk.link[lane], cb, rb, sb);
            }
            for lane in Lanes(leaves & !blk.single) {
                self.leaf_pairs(&a.nodes[blk.node[lane] as usize], &self.b.nodes[ib as usize]);
            }
            let inner = hits & !blk.leaf;
            // An inner child that nests is inside the sphere: |c - cb| + r <= rb.
            let inside = if self.aggregate { inner & nested } else { 0 };
            for lane in Lanes(inside) {
                let ca = Vec3::new(blk.x[lane], blk.y[lane], blk.z[lane]);
                if S::COLLECTS {
                    self.sink.nested(ca, blk.r[lane], self.b.spheres[sb as usize], blk.share[lane] * wb, false);
                    continue;
                }
                let l = Lens { volume: blk.share[lane] * wb, centroid: ca, depth: blk.r[lane] + rb - d2[lane].sqrt() };
                self.emit_aggregate(&l, ca, cb);
            }
            let mut descend = inner & !inside;
            if S::COLLECTS && self.aggregate {
                // Inside the sphere now, but nearer its surface than the margin: the list keeps the node and
                // its sphere, to settle whether it is still inside at each query.
                let (_, _, now) = four_against([blk.x, blk.y, blk.z], blk.r, blk.leaf, cb, rb, true, 0.0);
                for lane in Lanes(descend & now) {
                    self.sink.maybe_nested(blk.node[lane], sb, ib);
                }
                descend &= !now;
            }
            for lane in Lanes(descend) {
                if len < LOCAL_DEPTH {
                    self.local[len] = blk.link[lane];
                    len += 1;
                } else {
                    next.push((blk.node[lane], ib));
                }
            }
        }
    }

    /// Every overlap of A's subtree under inner node `ia` with B's sphere `sb` (in leaf `ib`), as the
    /// exact descent finds it (a neighbour list's node that has left the sphere it was inside).
    pub(super) fn subtree_against_sphere(&mut self, ia: u32, sb: u32, ib: u32, ws: &mut QueryWorkspace) {
        let s = self.b.spheres[sb as usize];
        ws.stack.clear();
        self.subtree_in_sphere(ia, self.tp(s.center), s.radius, sb, ib, &mut ws.stack);
        self.drain_stack(ws);
    }

    /// A node's bound in its own frame: the sphere itself for a one-sphere leaf (what its parent's
    /// block holds), else the node's bound.
    #[inline(always)]
    fn bound_of(tree: &InnerSphereTree, node: &Node) -> (Vec3, f32) {
        if node.leaf && node.count == 1 {
            let s = &tree.spheres[node.first as usize];
            (s.center, s.radius)
        } else {
            (node.bound.center, node.bound.radius)
        }
    }

    /// One pair of leaf spheres (A's sphere `sa` at `ca`, B's sphere `sb` at `cb`, both in A's frame).
    #[inline(always)]
    fn sphere_pair(&mut self, ca: Vec3, ra: f32, sa: u32, cb: Vec3, rb: f32, sb: u32) {
        if S::COLLECTS {
            self.sink.pair(sa, sb);
            return;
        }
        let weight = self.a.weights[sa as usize] * self.b.weights[sb as usize];
        if self.pairs.push(ca, ra, cb, rb, weight) {
            self.flush_pairs();
        }
    }

    /// Computes the queued sphere pairs' lenses four at once and reports them.
    pub(super) fn flush_pairs(&mut self) {
        let n = self.pairs.len;
        self.pairs.len = 0;
        let p = &self.pairs;
        for at in (0..n).step_by(4) {
            let v = |x: &[f32; PAIR_BATCH]| Vec4::from_slice(&x[at..at + 4]);
            let (ca, cb) = ([v(&p.ax), v(&p.ay), v(&p.az)], [v(&p.bx), v(&p.by), v(&p.bz)]);
            let mut lenses = lens_x4(ca, v(&p.ar), cb, v(&p.br));
            lenses.volume *= v(&p.w);
            let lanes = lenses.volume.cmpgt(Vec4::ZERO).bitmask() & ((1u32 << (n - at).min(4)) - 1);
            let mut left = lanes;
            while left != 0 {
                self.result.total_volume += lenses.volume[left.trailing_zeros() as usize];
                self.result.leaf_pairs += 1;
                left &= left - 1;
            }
            self.sink.four(&lenses, ca, cb, lanes);
        }
    }

    #[inline]
    fn leaf_pairs(&mut self, na: &Node, nb: &Node) {
        for ib in nb.range() {
            let sb = self.b.spheres[ib];
            let cb = self.tp(sb.center);
            for ia in na.range() {
                let sa = self.a.spheres[ia];
                self.sphere_pair(sa.center, sa.radius, ia as u32, cb, sb.radius, ib as u32);
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
                if d + na.bound.radius + self.margin() <= sb.radius {
                    let volume = na.mesh_share * self.b.weights[ib];
                    if S::COLLECTS {
                        self.sink.nested(na.bound.center, na.bound.radius, *sb, volume, false);
                        return true;
                    }
                    let l = Lens { volume, centroid: na.bound.center, depth: sb.radius + na.bound.radius - d };
                    self.emit_aggregate(&l, na.bound.center, c);
                    return true;
                }
            }
        } else if na.leaf {
            for ia in na.range() {
                let sa = &self.a.spheres[ia];
                let d = sa.center.distance(cb);
                if d + nb.bound.radius + self.margin() <= sa.radius {
                    let volume = nb.mesh_share * self.a.weights[ia];
                    if S::COLLECTS {
                        self.sink.nested(sa.center, sa.radius, nb.bound, volume, true);
                        return true;
                    }
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
            self.sink.one(l, ca, cb);
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
        self.sink.one(&l, na.bound.center, cb);
    }
}
