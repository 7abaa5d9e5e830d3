//! Small fixed-size helpers of the descent: the lanes of a mask, and sphere pairs queued for their
//! lenses.

use glam::Vec3;

/// The lanes whose bits are set in a mask, lowest first.
pub(super) struct Lanes(pub(super) u32);

impl Iterator for Lanes {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let lane = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(lane)
    }
}

/// How many sphere pairs wait for their lenses before they are computed four at once.
pub(super) const PAIR_BATCH: usize = 64;

/// Sphere pairs (both in A's frame) waiting for their lenses, structure of arrays.
pub(super) struct PairBatch {
    pub(super) ax: [f32; PAIR_BATCH],
    pub(super) ay: [f32; PAIR_BATCH],
    pub(super) az: [f32; PAIR_BATCH],
    pub(super) ar: [f32; PAIR_BATCH],
    pub(super) bx: [f32; PAIR_BATCH],
    pub(super) by: [f32; PAIR_BATCH],
    pub(super) bz: [f32; PAIR_BATCH],
    pub(super) br: [f32; PAIR_BATCH],
    /// Product of the two spheres' weights.
    pub(super) w: [f32; PAIR_BATCH],
    pub(super) len: usize,
}

impl PairBatch {
    pub(super) fn new() -> Self {
        let z = [0.0; PAIR_BATCH];
        Self { ax: z, ay: z, az: z, ar: z, bx: z, by: z, bz: z, br: z, w: z, len: 0 }
    }

    /// Queues a pair; true when the batch is full.
    #[inline(always)]
    pub(super) fn push(&mut self, ca: Vec3, ra: f32, cb: Vec3, rb: f32, w: f32) -> bool {
        let i = self.len;
        (self.ax[i], self.ay[i], self.az[i], self.ar[i]) = (ca.x, ca.y, ca.z, ra);
        (self.bx[i], self.by[i], self.bz[i], self.br[i]) = (cb.x, cb.y, cb.z, rb);
        self.w[i] = w;
        self.len = i + 1;
        self.len == PAIR_BATCH
    }
}
