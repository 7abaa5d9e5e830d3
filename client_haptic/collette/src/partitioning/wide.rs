//! The children of each inner node side by side (structure of arrays), for testing all four at once.
//!
//! Derived from the nodes whenever a tree is made or loaded, never stored in a file. A query that
//! descends into a node reads one block (its children's centres, radii, mesh shares and indices: 128 bytes)
//! instead of four scattered nodes, and tests the four children against a bound with four-wide
//! arithmetic. A child that is a leaf holding a single sphere (every leaf of a tree built here) is
//! stored as that sphere, so an overlap found in the block is already a sphere pair.

use super::block::{ChildBlock, NO_BLOCK};
use super::{InnerSphereTree, Node};
use glam::Vec4;

impl InnerSphereTree {
    /// Rebuilds the child blocks from the nodes; call after the nodes or their mesh shares change, and
    /// after validation (indices are trusted here).
    pub(crate) fn rebuild_blocks(&mut self) {
        self.blocks.clear();
        self.block_of.clear();
        self.block_of.resize(self.nodes.len(), NO_BLOCK);
        let mut count = 0;
        for (i, n) in self.nodes.iter().enumerate() {
            if !n.leaf {
                self.block_of[i] = count;
                count += 1;
            }
        }
        for n in &self.nodes {
            if n.leaf {
                continue;
            }
            let mut b = ChildBlock {
                x: Vec4::NAN,
                y: Vec4::NAN,
                z: Vec4::NAN,
                r: Vec4::ZERO,
                share: Vec4::ZERO,
                node: [0; 4],
                link: [NO_BLOCK; 4],
                leaf: 0,
                single: 0,
            };
            for (lane, c) in n.range().enumerate().take(4) {
                let child: &Node = &self.nodes[c];
                let bound = if child.leaf && child.count == 1 {
                    b.single |= 1 << lane;
                    b.link[lane] = child.first;
                    self.spheres[child.first as usize]
                } else {
                    child.bound
                };
                b.leaf |= (child.leaf as u32) << lane;
                b.node[lane] = c as u32;
                if !child.leaf {
                    b.link[lane] = self.block_of[c];
                }
                b.x[lane] = bound.center.x;
                b.y[lane] = bound.center.y;
                b.z[lane] = bound.center.z;
                b.r[lane] = bound.radius;
                b.share[lane] = child.mesh_share;
            }
            self.blocks.push(b);
        }
    }

    /// Block `index` (a [`ChildBlock::link`] entry of an inner child).
    #[inline(always)]
    pub(crate) fn block_at(&self, index: u32) -> &ChildBlock {
        &self.blocks[index as usize]
    }

    /// The child block of inner node `node`.
    #[inline(always)]
    pub(crate) fn block(&self, node: u32) -> &ChildBlock {
        &self.blocks[self.block_of[node as usize] as usize]
    }
}
