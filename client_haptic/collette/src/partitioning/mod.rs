//! The Inner Sphere Tree: packed leaf spheres under a wrapped hierarchy of bounding spheres.
//!
//! You need this module to inspect a tree (spheres, nodes, volumes); build one with
//! [`crate::packing::build`] and query it with [`crate::query`]. Split by operation: `build` (top-down
//! volume-weighted clustering), `traverse` (visiting nodes), `validate` (checking loaded trees).

mod block;
mod build;
mod traverse;
mod validate;
mod wide;

pub(crate) use block::ChildBlock;
pub use build::LEAF_SIZE;
pub use traverse::for_each_leaf_in_sphere;

use crate::shape::Sphere;

/// One node of the hierarchy. Inner nodes point at `count` consecutive child nodes; leaves point at
/// `count` consecutive spheres of [`InnerSphereTree::spheres`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    /// Sphere enclosing every leaf sphere below this node (wrapped around the leaves, not the children).
    pub bound: Sphere,
    /// Summed volume of the leaf spheres below this node.
    pub volume: f32,
    /// Volume of the mesh the leaf spheres below this node stand for: their volumes times their
    /// weights (see [`InnerSphereTree::weights`]).
    pub mesh_share: f32,
    /// Index of the first child node (inner) or first sphere (leaf).
    pub first: u32,
    /// Number of children (inner) or spheres (leaf).
    pub count: u32,
    /// True for a leaf node.
    pub leaf: bool,
}

impl Node {
    /// The index range of the node's children or spheres.
    #[inline]
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }
}

/// An Inner Sphere Tree: non-overlapping spheres inside one object, in the object's local frame.
///
/// Two trees are equal when their spheres, weights, nodes and mesh volume are (the child blocks are
/// derived from them).
#[derive(Clone)]
pub struct InnerSphereTree {
    pub(crate) spheres: Vec<Sphere>,
    pub(crate) weights: Vec<f32>,
    pub(crate) nodes: Vec<Node>,
    pub(crate) mesh_volume: f32,
    /// Each inner node's children side by side ([`wide`]), derived from `nodes`.
    pub(crate) blocks: Vec<ChildBlock>,
    /// Per node, its index in `blocks` (`u32::MAX` for leaves).
    pub(crate) block_of: Vec<u32>,
}

impl PartialEq for InnerSphereTree {
    fn eq(&self, other: &Self) -> bool {
        self.spheres == other.spheres
            && self.weights == other.weights
            && self.nodes == other.nodes
            && self.mesh_volume == other.mesh_volume
    }
}

impl std::fmt::Debug for InnerSphereTree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("InnerSphereTree")
            .field("spheres", &self.spheres)
            .field("weights", &self.weights)
            .field("nodes", &self.nodes)
            .field("mesh_volume", &self.mesh_volume)
            .finish_non_exhaustive()
    }
}

impl InnerSphereTree {
    /// The packed spheres (leaves), in hierarchy order.
    pub fn spheres(&self) -> &[Sphere] {
        &self.spheres
    }

    /// Per sphere (same order as [`InnerSphereTree::spheres`]): the volume of the mesh it stands for
    /// divided by its own volume (>= 1). The sphere itself plus its share of the gaps between the
    /// spheres and the surface: every gap point belongs to the sphere whose surface is nearest, so the
    /// shares add up to the mesh volume. Queries multiply each lens volume by both spheres' weights,
    /// which turns the packing's overlap volume (always short) into an estimate of the objects' own.
    /// All 1 for a tree built without a mesh ([`InnerSphereTree::from_spheres`], version-1 files).
    pub fn weights(&self) -> &[f32] {
        &self.weights
    }

    /// The nodes; the root is `nodes()[0]`.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The root node.
    pub fn root(&self) -> &Node {
        &self.nodes[0]
    }

    /// Exact volume of the mesh the tree was built from (mesh units³).
    pub fn mesh_volume(&self) -> f32 {
        self.mesh_volume
    }

    /// Summed volume of all spheres.
    pub fn packed_volume(&self) -> f32 {
        self.root().volume
    }

    /// Mesh volume the spheres stand for (the mesh volume once weighted, else the packed volume).
    pub fn mesh_share(&self) -> f32 {
        self.root().mesh_share
    }

    /// Packed volume / mesh volume.
    pub fn coverage(&self) -> f32 {
        if self.mesh_volume > 0.0 { self.packed_volume() / self.mesh_volume } else { 0.0 }
    }

    /// Depth of the hierarchy (1 for a single leaf).
    pub fn depth(&self) -> usize {
        fn walk(t: &InnerSphereTree, n: usize) -> usize {
            let node = &t.nodes[n];
            if node.leaf { 1 } else { 1 + node.range().map(|c| walk(t, c)).max().unwrap_or(0) }
        }
        walk(self, 0)
    }

    /// A copy with every length multiplied by `factor` (> 0), e.g. to convert mesh units to metres.
    pub fn scaled(&self, factor: f32) -> Self {
        let s = |x: Sphere| Sphere::new(x.center * factor, x.radius * factor);
        let v = factor * factor * factor;
        let mut scaled = Self {
            spheres: self.spheres.iter().map(|&x| s(x)).collect(),
            weights: self.weights.clone(),
            nodes: self
                .nodes
                .iter()
                .map(|n| Node { bound: s(n.bound), volume: n.volume * v, mesh_share: n.mesh_share * v, ..*n })
                .collect(),
            mesh_volume: self.mesh_volume * v,
            blocks: Vec::new(),
            block_of: Vec::new(),
        };
        scaled.rebuild_blocks();
        scaled
    }

    /// A copy whose spheres all weigh 1: its queries give the packing's own overlap volume.
    pub fn unweighted(&self) -> Self {
        let mut t = self.clone();
        t.weights.fill(1.0);
        for n in &mut t.nodes {
            n.mesh_share = n.volume;
        }
        t.rebuild_blocks();
        t
    }

    /// Sets the spheres' weights (one per sphere, in sphere order) and every node's mesh share.
    pub(crate) fn set_weights(&mut self, weights: Vec<f32>) {
        debug_assert_eq!(weights.len(), self.spheres.len());
        self.weights = weights;
        // Children come after their parent: in reverse order every child is done before its parent.
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let share: f64 = if n.leaf {
                n.range().map(|s| self.spheres[s].volume() as f64 * self.weights[s] as f64).sum()
            } else {
                n.range().map(|c| self.nodes[c].mesh_share as f64).sum()
            };
            self.nodes[i].mesh_share = share as f32;
        }
        self.rebuild_blocks();
    }
}
