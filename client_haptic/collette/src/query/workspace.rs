//! Scratch memory for queries, allocated once by the caller.

/// Stacks and queues reused by every query; create one per thread and keep it.
#[derive(Clone, Debug)]
pub struct QueryWorkspace {
    /// Depth-first stack of node pairs.
    pub(crate) stack: Vec<(u32, u32)>,
    /// Breadth-first ring of node pairs for budgeted queries (fixed capacity).
    pub(crate) ring: Vec<(u32, u32)>,
    /// Single-tree node stack.
    pub(crate) nodes: Vec<u32>,
    /// Measured cost of estimating one queued pair, nanoseconds: budgeted queries stop refining early
    /// enough to estimate everything still queued before their deadline.
    pub(crate) estimate_ns: f32,
}

impl Default for QueryWorkspace {
    fn default() -> Self {
        Self::new()
    }
}

impl QueryWorkspace {
    /// Capacity of the breadth-first ring; beyond it pairs are refined depth-first.
    pub const RING_CAPACITY: usize = 4096;

    /// A workspace with room for deep trees (allocates; call it once, off the hot path).
    pub fn new() -> Self {
        Self {
            stack: Vec::with_capacity(8192),
            ring: vec![(0, 0); Self::RING_CAPACITY],
            nodes: Vec::with_capacity(1024),
            estimate_ns: 60.0,
        }
    }
}
