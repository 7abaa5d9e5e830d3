//! What an overlap query may spend ([`Budget`]) and what it found ([`OverlapResult`]).

use std::time::Instant;

/// How much work a budgeted query may do before estimating the rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// No limit: the exact answer.
    Unlimited,
    /// Stop after visiting this many node pairs (deterministic, for tests and replays).
    NodePairs(u32),
    /// Stop at this instant (checked every few node pairs).
    Deadline(Instant),
}

impl Budget {
    /// Whether a single-tree query that has visited `visited` nodes must stop: the node count, or the
    /// clock every [`Self::CLOCK_STRIDE`] calls (`until_clock` counts them down; start it at 0).
    pub(crate) fn spent(&self, visited: u32, until_clock: &mut u32) -> bool {
        match *self {
            Budget::Unlimited => false,
            Budget::NodePairs(max) => visited >= max,
            Budget::Deadline(deadline) => {
                *until_clock = if *until_clock == 0 { Self::CLOCK_STRIDE } else { *until_clock - 1 };
                *until_clock == Self::CLOCK_STRIDE && Instant::now() >= deadline
            }
        }
    }

    /// Nodes a single-tree query visits between two looks at the clock.
    pub(crate) const CLOCK_STRIDE: u32 = 16;
}

/// Summary of an overlap query.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OverlapResult {
    /// Overlap volume, including `estimated_volume` (units³ of the trees).
    pub total_volume: f32,
    /// Part of `total_volume` estimated from inner nodes' summed volumes (budgeted queries only).
    pub estimated_volume: f32,
    /// Overlapping leaf-sphere pairs found exactly.
    pub leaf_pairs: u32,
    /// Contacts standing for a whole node inside one leaf sphere (aggregated queries only).
    pub aggregated_pairs: u32,
    /// Node pairs estimated instead of refined.
    pub estimated_pairs: u32,
    /// Node pairs visited: each tests the children of one node against the other node (four at once)
    /// and settles the child pairs that end the descent there.
    pub node_pairs: u32,
    /// False when the budget stopped the traversal.
    pub complete: bool,
}
