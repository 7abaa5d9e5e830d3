//! The exact aggregated overlap query with temporal coherence: a neighbour list kept from one query to
//! the next (a Verlet list with a skin, as molecular dynamics keeps its neighbour pairs).
//!
//! At 1 kHz a hand-held tool moves micrometres per tick, so the sphere pairs that overlap barely
//! change between queries, yet the plain query descends both trees from their roots every time. Here a
//! descent *collects*, with every bound grown by `skin`: each sphere pair that comes within `skin` of
//! overlapping; each node that lies inside one leaf sphere of the other tree with `skin` to spare (a
//! constant volume); and each node of A inside one sphere of B but nearer its surface than `skin`. As
//! long as no point of A has moved by `skin` relative to B since the pose the list was collected for, no
//! pair outside the list can overlap (its gap was at least `skin`) and no node of the second kind can
//! have left its sphere, so the exact answer is the list's alone: the pairs' lenses four at once from
//! contiguous memory, the nodes' volumes, and for a node of the third kind either its volume (still
//! inside) or the exact descent of its subtree against that one sphere. Once A has moved farther, the
//! list is collected again, for a pose 0.7 skin ahead along A's last step, so that it serves 1.7
//! skins of a steady motion rather than one.
//!
//! The volume is the plain query's (up to the order of the f32 sums), and so are the contacts, except
//! that a node the plain query settles inside a leaf sphere may come as its sphere pairs here (when it
//! straddled that sphere's surface or was within the skin of another sphere when the list was
//! collected): same volume, more contacts.

use super::affine::WideAffine;
use super::batch::Lanes;
use super::engine::Engine;
use super::fallback_normal;
use super::result::{Budget, OverlapResult};
use super::sink::{Contacts, Sink};
use crate::error::SkinError;
use crate::partitioning::InnerSphereTree;
use crate::query::QueryWorkspace;
use crate::shape::{Lens4, Sphere};
use glam::{Affine3A, Quat, Vec3, Vec4};
use haptic_common::{ContactSet, Pose};

/// What a [`CoherentOverlap`] did over its queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CoherenceStats {
    /// Queries answered.
    pub queries: u64,
    /// Queries that collected the list anew (the first, and each after A moved by the skin).
    pub collections: u64,
    /// Collections that found more candidates than the list holds: those queries were answered by the
    /// plain exact query instead (size the list with [`CoherentOverlap::with_capacity`]).
    pub overflows: u64,
}

/// The neighbour list of one pair of trees, kept between exact overlap queries; see the module docs.
///
/// Create one per watched pair, off the hot path (it allocates its lists once), and pass it to every
/// query of that pair: [`CoherentOverlap::query`]. In steady state a query allocates nothing.
#[derive(Clone, Debug)]
pub struct CoherentOverlap {
    skin: f32,
    /// The two trees the list was collected for (their spheres' addresses and counts).
    trees: Option<[usize; 4]>,
    /// A's pose in B's frame the list was collected for (ahead of where A was then).
    anchor: Option<Pose>,
    /// A's pose in B's frame at the last query.
    last: Option<Pose>,
    /// Candidate sphere pairs (A's side in A's frame, B's in B's frame), padded to whole groups of eight.
    pairs: Columns<9>,
    /// Nodes inside a leaf sphere of the other tree: A's side (x, y, z, r), B's side (x, y, z, r), the
    /// volume, and 1 where the centroid is B's side (B's node inside A's sphere), padded likewise.
    nested: Columns<10>,
    /// Nodes of A inside a leaf sphere of B but nearer its surface than the skin: A's side (x, y, z,
    /// r), B's sphere (x, y, z, r), the volume; and per row A's node, B's sphere and B's leaf.
    maybe: Columns<9>,
    maybe_ids: Vec<[u32; 3]>,
    overflow: bool,
    stats: CoherenceStats,
}

/// `N` columns of f32 with room for `capacity` rows (allocated once), padded to a multiple of eight.
#[derive(Clone, Debug)]
struct Columns<const N: usize> {
    col: [Vec<f32>; N],
    len: usize,
}

impl<const N: usize> Columns<N> {
    fn with_capacity(capacity: usize) -> Self {
        Self { col: std::array::from_fn(|_| vec![0.0; capacity.next_multiple_of(eight::LANES)]), len: 0 }
    }

    fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends a row; false (and nothing appended) when the list is full.
    #[inline(always)]
    fn push(&mut self, row: [f32; N]) -> bool {
        let i = self.len;
        if i == self.col[0].len() {
            return false;
        }
        for (c, v) in self.col.iter_mut().zip(row) {
            c[i] = v;
        }
        self.len = i + 1;
        true
    }

    /// True when no more rows fit.
    fn is_full(&self) -> bool {
        self.len == self.col[0].len()
    }

    /// Zeroes the rows after the last up to a multiple of eight (zero radii and volumes count nothing).
    fn pad(&mut self) {
        let end = self.len.next_multiple_of(eight::LANES).min(self.col[0].len());
        for c in &mut self.col {
            c[self.len..end].fill(0.0);
        }
    }

    /// Column `k`'s four entries from `at`.
    #[inline(always)]
    fn four(&self, k: usize, at: usize) -> Vec4 {
        Vec4::from_slice(&self.col[k][at..at + 4])
    }

    /// The four rows from `at` as two spheres each, from columns 0–3 (A's side, A's frame) and 4–7
    /// (B's side, moved into A's frame by `wide`): centres, radii and squared centre distances.
    #[inline(always)]
    fn sides(&self, at: usize, wide: &WideAffine) -> ([Vec4; 3], Vec4, [Vec4; 3], Vec4, Vec4) {
        let ca = [self.four(0, at), self.four(1, at), self.four(2, at)];
        let cb = wide.point(self.four(4, at), self.four(5, at), self.four(6, at));
        let (dx, dy, dz) = (ca[0] - cb[0], ca[1] - cb[1], ca[2] - cb[2]);
        (ca, self.four(3, at), cb, self.four(7, at), dx * dx + dy * dy + dz * dz)
    }
}

impl CoherentOverlap {
    /// Room for this many candidate pairs (and as many nodes of each kind) by default: about 8 MB,
    /// five times what the bunny scene's 10k-sphere trees need with the default skin.
    pub const DEFAULT_CAPACITY: usize = 1 << 16;

    /// A list collected with `skin` (tree units: how far A may move relative to B before the list is
    /// collected again). A larger skin lasts more ticks but holds more pairs to evaluate each tick; 0
    /// collects on every query. Errors when `skin` is negative or not finite.
    pub fn new(skin: f32) -> Result<Self, SkinError> {
        Self::with_capacity(skin, Self::DEFAULT_CAPACITY)
    }

    /// [`CoherentOverlap::new`] with room for `capacity` candidate pairs and as many nested nodes.
    pub fn with_capacity(skin: f32, capacity: usize) -> Result<Self, SkinError> {
        if !(skin.is_finite() && skin >= 0.0) {
            return Err(SkinError(skin));
        }
        Ok(Self {
            skin,
            trees: None,
            anchor: None,
            last: None,
            pairs: Columns::with_capacity(capacity),
            nested: Columns::with_capacity(capacity),
            maybe: Columns::with_capacity(capacity),
            maybe_ids: Vec::with_capacity(capacity),
            overflow: false,
            stats: CoherenceStats::default(),
        })
    }

    /// A skin suited to two trees: eight times the smaller of their median leaf-sphere radii (the
    /// bunny scene's 10k-sphere trees: about 0.5 mm, some twenty ticks of its tool in the deep
    /// grazing stretch; the skins tried there are in docs/collette.md).
    pub fn skin_for(a: &InnerSphereTree, b: &InnerSphereTree) -> f32 {
        let median = |t: &InnerSphereTree| {
            let mut r: Vec<f32> = t.spheres().iter().map(|s| s.radius).collect();
            r.sort_by(f32::total_cmp);
            r.get(r.len() / 2).copied().unwrap_or(0.0)
        };
        8.0 * median(a).min(median(b))
    }

    /// The skin the list is collected with.
    pub fn skin(&self) -> f32 {
        self.skin
    }

    /// What the list did so far.
    pub fn stats(&self) -> CoherenceStats {
        self.stats
    }

    /// Candidate sphere pairs and nodes (inside a sphere of the other tree with the skin to spare, or
    /// less) in the current list.
    pub fn len(&self) -> (usize, usize) {
        (self.pairs.len, self.nested.len + self.maybe.len)
    }

    /// True when no list is held (before the first query, after [`CoherentOverlap::invalidate`]).
    pub fn is_empty(&self) -> bool {
        self.anchor.is_none()
    }

    /// Drops the list: the next query collects it anew (call it when a tree's spheres change in place).
    pub fn invalidate(&mut self) {
        self.anchor = None;
    }

    /// The exact aggregated overlap of `a` at `pose_a` and `b` at `pose_b`, as
    /// [`super::overlap_budgeted`] with [`Budget::Unlimited`] gives it, from the list (collected
    /// first when there is none, the trees are others, or A has moved by the skin since).
    /// `node_pairs` counts the node pairs visited: by the collecting descent, if the list was collected,
    /// and by the nodes descended against a sphere they have left.
    pub fn query(
        &mut self,
        a: &InnerSphereTree,
        pose_a: &Pose,
        b: &InnerSphereTree,
        pose_b: &Pose,
        ws: &mut QueryWorkspace,
        out: &mut ContactSet,
    ) -> OverlapResult {
        self.stats.queries += 1;
        let a_in_b = pose_b.relative_to(pose_a);
        let trees = [a.spheres.as_ptr() as usize, a.spheres.len(), b.spheres.as_ptr() as usize, b.spheres.len()];
        let mut result = OverlapResult { complete: true, ..OverlapResult::default() };
        let same_trees = self.trees == Some(trees);
        if !(same_trees && self.anchor.is_some_and(|then| self.moved(&then, &a_in_b, a, b) < self.skin)) {
            let anchor = if same_trees { self.ahead(&a_in_b, a, b) } else { a_in_b };
            result.node_pairs = self.collect(a, b, anchor.inverse(), ws);
            self.trees = Some(trees);
            self.anchor = Some(anchor);
        }
        self.last = Some(a_in_b);
        out.clear();
        let to_world = Affine3A::from_rotation_translation(pose_a.rotation, pose_a.translation);
        let sink = Contacts::new(to_world, fallback_normal(a, b, pose_a, pose_b), out);
        let mut engine = Engine::new(a, b, pose_a.relative_to(pose_b), Budget::Unlimited, true, sink);
        if self.overflow {
            // The list is incomplete: answer this query in full and collect again next time.
            self.anchor = None;
            engine.run_depth_first(ws);
        } else {
            self.evaluate(&mut engine, ws);
            engine.flush_pairs();
        }
        let visited = result.node_pairs;
        result = engine.result;
        result.node_pairs += visited;
        out.total_volume = result.total_volume;
        out.estimated_volume = 0.0;
        out.truncated |= !result.complete;
        result
    }

    /// How far any point of A can have moved relative to B (or B relative to A: a rotation moves the
    /// points of the smaller bounding sphere less) between A's poses `then` and `now` in B's frame,
    /// plus what f32 rounding could add: every sphere pair's gap changes by less than that.
    fn moved(&self, then: &Pose, now: &Pose, a: &InnerSphereTree, b: &InnerSphereTree) -> f32 {
        let (ba, bb) = (a.root().bound, b.root().bound);
        // |(R - R0) v| <= 2 sin(θ/2) |v| for the rotation θ between them; sin(θ/2) is the vector part's length.
        let chord = 2.0 * (now.rotation * then.rotation.inverse()).xyz().length();
        let moved = |now: &Pose, then: &Pose, bound: Sphere| {
            (now.transform_point(bound.center) - then.transform_point(bound.center)).length() + chord * bound.radius
        };
        let moved = moved(now, then, ba).min(moved(&now.inverse(), &then.inverse(), bb));
        let scale = now.translation.length() + ba.center.length() + ba.radius + bb.center.length() + bb.radius;
        moved + 8.0 * f32::EPSILON * scale
    }

    /// Where to collect the list when A is at `now`: 0.7 skin ahead along its last step (the list then
    /// serves the way there and a skin beyond), or `now` when it has no last step or stands still.
    fn ahead(&self, now: &Pose, a: &InnerSphereTree, b: &InnerSphereTree) -> Pose {
        let Some(last) = self.last else { return *now };
        let step = self.moved(&last, now, a, b);
        // NaN (a step of 0 with a skin of 0) and less than one step ahead both mean: collect at `now`.
        let steps = (0.7 * self.skin / step).floor().min(1000.0);
        if steps.is_nan() || steps < 1.0 {
            return *now;
        }
        let turn = (now.rotation * last.rotation.inverse()).to_scaled_axis();
        let ahead = Pose::new(
            now.translation + (now.translation - last.translation) * steps,
            (Quat::from_scaled_axis(turn * steps) * now.rotation).normalize(),
        );
        // A turn and a shift do not add up exactly along a curve: keep the list answering from `now` on.
        if ahead.is_finite() && self.moved(&ahead, now, a, b) < 0.9 * self.skin { ahead } else { *now }
    }

    /// Collects the list at relative pose `pos12` (B's frame into A's); returns the node pairs visited.
    fn collect(&mut self, a: &InnerSphereTree, b: &InnerSphereTree, pos12: Pose, ws: &mut QueryWorkspace) -> u32 {
        self.stats.collections += 1;
        self.pairs.clear();
        self.nested.clear();
        self.maybe.clear();
        self.maybe_ids.clear();
        let collector = Collector { list: self, a, b };
        let mut engine = Engine::new(a, b, pos12, Budget::Unlimited, true, collector);
        engine.run_depth_first(ws);
        let visited = engine.result.node_pairs;
        self.overflow = self.pairs.is_full() || self.nested.is_full() || self.maybe.is_full();
        if self.overflow {
            self.stats.overflows += 1;
        }
        self.pairs.pad();
        self.nested.pad();
        self.maybe.pad();
        visited
    }

    /// The list's lenses and nodes' volumes at the engine's pose, into its sink and result; a node
    /// that has left the sphere it was inside is descended against it.
    fn evaluate<S: Sink>(&self, engine: &mut Engine<'_, S>, ws: &mut QueryWorkspace) {
        let wide = engine.wide;
        let mut aggregated = 0;
        let found = eight::pairs(&self.pairs.col, self.pairs.len, &engine.pos12, &mut engine.sink);
        let (mut total, leaf_pairs) = (Vec4::new(found.volume, 0.0, 0.0, 0.0), found.pairs);
        let n = &self.nested;
        for at in (0..n.len).step_by(4) {
            let (ca, ra, cb, rb, d2) = n.sides(at, &wide);
            let volume = n.four(8, at);
            let b_side = n.four(9, at).cmpgt(Vec4::ZERO);
            let d = d2.sqrt();
            let centroid = std::array::from_fn(|k| Vec4::select(b_side, cb[k], ca[k]));
            let lanes = volume.cmpgt(Vec4::ZERO).bitmask();
            total += volume;
            aggregated += lanes.count_ones();
            engine.sink.four(&Lens4 { volume, centroid, depth: ra + rb - d, inv_d: d.recip() }, ca, cb, lanes);
        }
        let m = &self.maybe;
        for at in (0..m.len).step_by(4) {
            let (ca, ra, cb, rb, d2) = m.sides(at, &wide);
            let gap = rb - ra;
            let rows = (1u32 << (m.len - at).min(4)) - 1;
            let inside = d2.cmple(gap * gap).bitmask() & gap.cmpge(Vec4::ZERO).bitmask() & rows;
            if inside != 0 {
                let volume = Vec4::select(
                    glam::BVec4A::from(std::array::from_fn(|k| inside >> k & 1 != 0)),
                    m.four(8, at),
                    Vec4::ZERO,
                );
                total += volume;
                aggregated += inside.count_ones();
                let d = d2.sqrt();
                let lens = Lens4 { volume, centroid: ca, depth: ra + rb - d, inv_d: d.recip() };
                engine.sink.four(&lens, ca, cb, inside);
            }
            for lane in Lanes(rows & !inside) {
                let [node, sb, ib] = self.maybe_ids[at + lane];
                engine.subtree_against_sphere(node, sb, ib, ws);
            }
        }
        engine.result.total_volume += total.element_sum();
        engine.result.leaf_pairs += leaf_pairs;
        engine.result.aggregated_pairs += aggregated;
    }
}

/// The sink of the collecting descent: candidates into the list.
struct Collector<'l, 't> {
    list: &'l mut CoherentOverlap,
    a: &'t InnerSphereTree,
    b: &'t InnerSphereTree,
}

impl Sink for Collector<'_, '_> {
    const COLLECTS: bool = true;

    fn one(&mut self, _: &crate::shape::Lens, _: Vec3, _: Vec3) {}

    fn four(&mut self, _: &Lens4, _: [Vec4; 3], _: [Vec4; 3], _: u32) {}

    #[inline(always)]
    fn margin(&self) -> f32 {
        self.list.skin
    }

    #[inline]
    fn pair(&mut self, sa: u32, sb: u32) {
        let (a, b) = (self.a.spheres[sa as usize], self.b.spheres[sb as usize]);
        let w = self.a.weights[sa as usize] * self.b.weights[sb as usize];
        let row = [a.center.x, a.center.y, a.center.z, a.radius, b.center.x, b.center.y, b.center.z, b.radius, w];
        self.list.pairs.push(row);
    }

    fn maybe_nested(&mut self, node: u32, sb: u32, ib: u32) {
        // An inner node's block entry is its own bound and mesh share.
        let (n, pb) = (&self.a.nodes[node as usize], self.b.spheres[sb as usize]);
        let (ca, c) = (n.bound.center, pb.center);
        let volume = n.mesh_share * self.b.weights[sb as usize];
        let row = [ca.x, ca.y, ca.z, n.bound.radius, c.x, c.y, c.z, pb.radius, volume];
        if self.list.maybe.push(row) {
            self.list.maybe_ids.push([node, sb, ib]);
        }
    }

    #[inline]
    fn nested(&mut self, ca: Vec3, ra: f32, pb: Sphere, volume: f32, b_inside: bool) {
        if volume > 0.0 {
            let (c, r) = (pb.center, pb.radius);
            let row = [ca.x, ca.y, ca.z, ra, c.x, c.y, c.z, r, volume, if b_inside { 1.0 } else { 0.0 }];
            self.list.nested.push(row);
        }
    }
}

mod eight;
#[cfg(test)]
mod tests;
