//! How close collette's overlap volume is to the real intersection volume of the two meshes.
//!
//! For each mesh pair, random poses (uniform rotation, the first object's centre uniform in the second's
//! box) are kept when the objects really overlap (at least `--min-overlap` of the smaller volume). At
//! each pose the reference is a Monte Carlo estimate: `--samples` stratified points inside the first
//! mesh (one jittered point per grid cell), each tested against the second mesh (parry3d's
//! pseudo-normal point containment, behind a voxel grid that answers the points far from the surface).
//! collette's exact (aggregated) overlap volume is divided by it, for each sphere count (`N` for both
//! trees, or `A:B` to pack the two meshes differently and see whose packing the error comes from).
//!
//! ```text
//! cargo run --release -p collette_ist --example volume_accuracy -- --poses 300 --samples 1000000
//! cargo run --release -p collette_ist --example volume_accuracy -- --pairs gem-bunny --spheres 10000,40000:10000,10000:40000
//! ```
//!
//! Prints, per pair and sphere count, the ratio's p5 / p50 / p95 (and min / max): the packing's own
//! volume (the lens sum; always short with `--surface-offset 0`), the volume the trees stand for
//! (each sphere weighted by the share of the mesh it stands for), and A's tree measured against B's
//! signed distance grid (`overlap_field`, the grid as fine as B's packing grid).

use clap::Parser;
use collette::scene::{SphereCounts, brilliant_cut, default_bunny_path, load_bunny};
use collette::shape::{box_buffers, torus_buffers, uv_sphere_buffers};
use collette::{
    BuildOptions, InnerSphereTree, Pose, QueryWorkspace, SignedDistanceGrid, TriMesh, build, overlap_field_volume,
    overlap_volume,
};
use glam::{Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "collette's overlap volume against the exact intersection volume, at random poses")]
struct Args {
    /// Poses kept per mesh pair.
    #[arg(long, default_value_t = 300)]
    poses: usize,
    /// Monte Carlo points inside the first mesh of each pair.
    #[arg(long, default_value_t = 1_000_000)]
    samples: usize,
    /// Sphere counts of the trees: N for both, or A:B (the pair's first mesh gets A, its second B).
    #[arg(long, value_delimiter = ',', default_value = "1000,10000")]
    spheres: Vec<SphereCounts>,
    /// Mesh pairs: torus-bunny, gem-bunny, bunny-bunny, ball-box.
    #[arg(long, value_delimiter = ',', default_value = "torus-bunny,gem-bunny,bunny-bunny,ball-box")]
    pairs: Vec<String>,
    /// Smallest overlap kept, as a fraction of the smaller object's volume.
    #[arg(long, default_value_t = 0.01)]
    min_overlap: f64,
    /// Seed of the poses and the samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// How far the spheres may reach past each surface, in voxels of its tree's grid
    /// (`BuildOptions::surface_offset`; 0 packs inside the meshes, as collette did until 2026-12-05).
    #[arg(long, default_value_t = BuildOptions::DEFAULT_SURFACE_OFFSET)]
    surface_offset: f32,
}

fn mesh(name: &str) -> Result<TriMesh, String> {
    let closed = |(v, t): (Vec<Vec3>, Vec<[u32; 3]>)| TriMesh::new(v, t).map_err(|e| format!("{name}: {e}"));
    match name {
        // Metres, the scene's sizes: a 10 cm bunny; the torus R 3, r 1 in the bunny's own units.
        "bunny" => load_bunny(default_bunny_path()).map_err(|e| format!("bunny: {e}")),
        "torus" => closed(torus_buffers(0.03, 0.01, 96, 48)),
        "gem" => Ok(brilliant_cut(0.01)),
        "ball" => closed(uv_sphere_buffers(0.03, 48, 96)),
        "box" => closed(box_buffers(Vec3::new(0.04, 0.03, 0.02))),
        other => Err(format!("unknown mesh {other:?} (torus, bunny, gem, ball, box)")),
    }
}

/// A mesh's inside (collette's exact reference), and stratified points in it.
struct Solid(collette::shape::Solid);

impl Solid {
    fn new(mesh: &TriMesh) -> Self {
        Self(collette::shape::Solid::new(mesh, 96))
    }

    fn contains(&self, p: Vec3) -> bool {
        self.0.contains(p)
    }

    /// About `n` stratified points inside the mesh: one jittered point per cell of a grid over its box.
    fn samples(&self, mesh: &TriMesh, n: usize, rng: &mut ChaCha8Rng) -> Vec<Vec3> {
        let aabb = mesh.aabb();
        let cell = (self.0.volume() / n as f64).cbrt() as f32;
        let cells = [0, 1, 2].map(|a| (aabb.extents()[a] / cell).ceil().max(1.0) as usize);
        let mut candidates = Vec::with_capacity(cells.iter().product());
        for z in 0..cells[2] {
            for y in 0..cells[1] {
                for x in 0..cells[0] {
                    let jitter = Vec3::new(rng.random(), rng.random(), rng.random());
                    candidates.push(aabb.min + (Vec3::new(x as f32, y as f32, z as f32) + jitter) * cell);
                }
            }
        }
        candidates.into_par_iter().filter(|&p| self.contains(p)).collect()
    }
}

/// A uniformly random rotation (Shoemake).
fn random_rotation(rng: &mut ChaCha8Rng) -> Quat {
    let (u1, u2, u3): (f32, f32, f32) = (rng.random(), rng.random(), rng.random());
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f32::consts::TAU * u2, std::f32::consts::TAU * u3);
    Quat::from_xyzw(a * t2.sin(), a * t2.cos(), b * t3.sin(), b * t3.cos()).normalize()
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    let args = Args::parse();
    if let Err(e) = run(&args) {
        eprintln!("volume_accuracy: {e}");
        std::process::exit(1);
    }
}

fn run(args: &Args) -> Result<(), String> {
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    println!(
        "| pair | spheres | coverage A / B | poses | packing volume ÷ exact, p5 / p50 / p95 (min–max) | weighted volume ÷ exact, p5 / p50 / p95 (min–max) | A's tree against B's distance grid ÷ exact, p5 / p50 / p95 (min–max) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for pair in &args.pairs {
        let (na, nb) = pair.split_once('-').ok_or_else(|| format!("pair {pair:?} is not A-B"))?;
        let (ma, mb) = (mesh(na)?, mesh(nb)?);
        let started = Instant::now();
        let (sa, sb) = (Solid::new(&ma), Solid::new(&mb));
        let pool = sa.samples(&ma, args.samples, &mut rng);
        let smaller = sa.0.volume().min(sb.0.volume());
        let b_box = mb.aabb();
        let mut poses = Vec::with_capacity(args.poses);
        let mut attempts = 0;
        while poses.len() < args.poses && attempts < 50 * args.poses {
            attempts += 1;
            let t = Vec3::new(rng.random(), rng.random(), rng.random());
            let pose = Pose { rotation: random_rotation(&mut rng), translation: b_box.min + t * b_box.extents() };
            let hits = pool.par_iter().filter(|&&p| sb.contains(pose.transform_point(p))).count();
            let exact = sa.0.volume() * hits as f64 / pool.len() as f64;
            if exact >= args.min_overlap * smaller {
                poses.push((pose, exact));
            }
        }
        eprintln!(
            "{pair}: {} poses of {attempts} tried, {} samples inside {na}, reference {:.1} s",
            poses.len(),
            pool.len(),
            started.elapsed().as_secs_f64()
        );
        for &counts in &args.spheres {
            let options = |n: usize| BuildOptions { surface_offset: args.surface_offset, ..BuildOptions::spheres(n) };
            let tree = |m: &TriMesh, n: usize| -> Result<InnerSphereTree, String> {
                build(m, &options(n), &mut |_| {}).map(|(t, _)| t).map_err(|e| e.to_string())
            };
            let (ta, tb) = (tree(&ma, counts.a)?, tree(&mb, counts.b)?);
            let (ua, ub) = (ta.unweighted(), tb.unweighted());
            let mut ws = QueryWorkspace::new();
            // B's distance grid at the resolution of B's packing grid.
            let grid = SignedDistanceGrid::new(&mb, options(counts.b).resolution()).map_err(|e| e.to_string())?;
            let mut field: Vec<f64> = poses
                .iter()
                .map(|(pose, exact)| {
                    overlap_field_volume(&ta, pose, &tb, &grid, &Pose::IDENTITY, &mut ws).total_volume as f64 / exact
                })
                .collect();
            field.sort_by(f64::total_cmp);
            let mut ratios = |a: &InnerSphereTree, b: &InnerSphereTree| {
                let mut r: Vec<f64> = poses
                    .iter()
                    .map(|(pose, exact)| {
                        overlap_volume(a, pose, b, &Pose::IDENTITY, &mut ws).total_volume as f64 / exact
                    })
                    .collect();
                r.sort_by(f64::total_cmp);
                r
            };
            let show = |r: &[f64]| {
                format!(
                    "{:.3} / {:.3} / {:.3} ({:.3}–{:.3})",
                    percentile(r, 0.05),
                    percentile(r, 0.5),
                    percentile(r, 0.95),
                    r[0],
                    r[r.len() - 1]
                )
            };
            let (packed, weighted) = (ratios(&ua, &ub), ratios(&ta, &tb));
            if packed.is_empty() {
                return Err(format!("{pair}: no pose overlaps by {} of the smaller volume", args.min_overlap));
            }
            println!(
                "| {pair} | {counts} | {:.3} / {:.3} | {} | {} | {} | {} |",
                ta.coverage(),
                tb.coverage(),
                packed.len(),
                show(&packed),
                show(&weighted),
                show(&field)
            );
        }
    }
    Ok(())
}
