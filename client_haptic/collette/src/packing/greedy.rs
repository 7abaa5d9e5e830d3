//! Greedy largest-free-sphere packing on a voxel distance field (the IST method).

use super::distance_field::DistanceField;
use super::refine::Refiner;
use crate::shape::Sphere;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::BinaryHeap;

/// When to stop packing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StopRule {
    pub max_spheres: usize,
    pub target_volume: f64,
    pub min_radius: f32,
}

/// Heap key: free radius bits (positive floats order like integers), ties broken towards the lower index.
#[inline]
fn key(radius: f32, index: usize) -> u64 {
    ((radius.to_bits() as u64) << 32) | (u32::MAX - index as u32) as u64
}

/// Packs non-overlapping spheres centred on interior voxels, largest free radius first.
///
/// Each voxel keeps its free radius: the distance to the surface minus nothing, then minus every placed
/// sphere (`|p − c| − r`). Stale heap entries are re-queued lazily, so the result is deterministic.
pub(crate) fn pack(
    field: &DistanceField,
    stop: StopRule,
    mut refiner: Option<&mut Refiner>,
    progress: &mut dyn FnMut(usize, f64),
) -> Vec<Sphere> {
    let mut free = field.distance.clone();
    let mut heap: BinaryHeap<u64> =
        free.iter().enumerate().filter(|(_, d)| **d >= stop.min_radius && **d > 0.0).map(|(i, &d)| key(d, i)).collect();
    let mut spheres = Vec::with_capacity(stop.max_spheres.min(1 << 20));
    let mut packed = 0.0f64;
    let report_every = (stop.max_spheres / 100).max(1);
    while spheres.len() < stop.max_spheres && packed < stop.target_volume {
        let Some(top) = heap.pop() else { break };
        let index = (u32::MAX - (top & 0xffff_ffff) as u32) as usize;
        let stored = f32::from_bits((top >> 32) as u32);
        let current = free[index];
        if current < stored {
            if current >= stop.min_radius && current > 0.0 {
                heap.push(key(current, index));
            }
            continue;
        }
        let center = field.voxel_center(index);
        let sphere = match refiner.as_deref_mut() {
            Some(r) => {
                let s = r.refine(center, current);
                r.insert(s);
                s
            }
            None => Sphere::new(center, current),
        };
        spheres.push(sphere);
        packed += sphere.volume() as f64;
        shrink_free_radii(field, &mut free, sphere.center, sphere.radius);
        if spheres.len() % report_every == 0 {
            progress(spheres.len(), packed);
        }
    }
    progress(spheres.len(), packed);
    spheres
}

/// Lowers the free radius of every voxel the new sphere can affect (those within 2r: no free radius
/// exceeds r, the largest one, so farther voxels cannot change). Large spheres update slabs in parallel.
fn shrink_free_radii(field: &DistanceField, free: &mut [f32], c: Vec3, r: f32) {
    let h = field.voxel_size;
    let [nx, ny, nz] = field.dims;
    let reach = 2.0 * r + h;
    let lo = ((c - reach - field.origin) / h).floor().max(Vec3::ZERO);
    let hi = ((c + reach - field.origin) / h).ceil();
    let (i0, j0, k0) = (lo.x as usize, lo.y as usize, lo.z as usize);
    let (i1, j1, k1) = ((hi.x as usize + 1).min(nx), (hi.y as usize + 1).min(ny), (hi.z as usize + 1).min(nz));
    if i0 >= i1 || j0 >= j1 || k0 >= k1 {
        return;
    }
    let update_slab = |k: usize, slab: &mut [f32]| {
        let z = field.origin.z + k as f32 * h - c.z;
        for j in j0..j1 {
            let y = field.origin.y + j as f32 * h - c.y;
            let yz = y * y + z * z;
            let row = &mut slab[j * nx..(j + 1) * nx];
            for (i, f) in row.iter_mut().enumerate().take(i1).skip(i0) {
                if *f <= 0.0 {
                    continue;
                }
                let x = field.origin.x + i as f32 * h - c.x;
                let d = (x * x + yz).sqrt() - r;
                if d < *f {
                    // Covered voxels get a negative radius and are never picked again.
                    *f = if d <= 0.0 { -1.0 } else { d };
                }
            }
        }
    };
    let slabs = &mut free[k0 * nx * ny..k1 * nx * ny];
    let work = (i1 - i0) * (j1 - j0) * (k1 - k0);
    if work > 64 * 1024 {
        slabs.par_chunks_mut(nx * ny).enumerate().for_each(|(dk, slab)| update_slab(k0 + dk, slab));
    } else {
        for (dk, slab) in slabs.chunks_mut(nx * ny).enumerate() {
            update_slab(k0 + dk, slab);
        }
    }
}
