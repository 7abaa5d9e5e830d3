//! One inner node's children side by side: the block a query reads instead of four scattered nodes
//! (built by `wide.rs`).

use glam::Vec4;

/// Index of "no block" in `InnerSphereTree::block_of` (leaf nodes).
pub(crate) const NO_BLOCK: u32 = u32::MAX;

/// Up to four children of one inner node. Unused lanes have NaN centres, so no test ever hits them.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct ChildBlock {
    /// Centres' x, y, z and radii of the children's bounds (the sphere itself for a one-sphere leaf).
    pub x: Vec4,
    pub y: Vec4,
    pub z: Vec4,
    pub r: Vec4,
    /// The children's mesh shares (`Node::mesh_share`).
    pub share: Vec4,
    /// Node index of each child.
    pub node: [u32; 4],
    /// Per child: its sphere's index for a one-sphere leaf, its block's index for an inner node
    /// ([`NO_BLOCK`] for a leaf of several spheres).
    pub link: [u32; 4],
    /// Bit i set: child i is a leaf.
    pub leaf: u32,
    /// Bit i set: child i is a leaf holding exactly one sphere.
    pub single: u32,
}

const _: () = assert!(std::mem::size_of::<ChildBlock>() == 128, "a block is two cache lines");
