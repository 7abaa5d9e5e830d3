//! Times the exact (aggregated) overlap query alone over the benchmark scene's 35,000 poses: a quick
//! loop for working on the query, where the full `bunny_scene` bench also runs every other query.
//!
//! ```text
//! cargo run --release -p collette_ist --example exact_query -- --spheres 10000
//! ```
//!
//! Prints the query time's p50 / p99 / p99.9 / max (least of `--runs` runs per pose, which filters out
//! the machine taking the core away), the work at the slowest pose, and a checksum of every pose's
//! volume and contact count; `--dump FILE` writes one line per pose (volume, contacts) to compare two
//! versions of the query.
//!
//! `--coherent` answers the poses in order, once each, with the temporal-coherence query
//! (`CoherentOverlap`, `--skin-um` to choose its skin) and splits the times into the poses that reused
//! the neighbour list and those that collected it; its volume checksum matches the plain query's.
//!
//! `--field` times the gem's tree against the bunny's signed distance grid instead (`overlap_field`,
//! the grid as fine as the bunny's packing grid): the query that follows the bunny's surface.

use clap::Parser;
use collette::scene::{SphereCounts, brilliant_cut, default_bunny_path, load_bunny, trajectory};
use collette::{
    Budget, BuildOptions, CoherentOverlap, ContactSet, InnerSphereTree, Pose, QueryWorkspace, SignedDistanceGrid,
    TriMesh, build, overlap_budgeted, overlap_field,
};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "time the exact aggregated overlap query over the bunny scene's trajectory")]
struct Args {
    /// Spheres per tree (tool and bunny), or TOOL:BUNNY.
    #[arg(long, default_value = "10000")]
    spheres: SphereCounts,
    /// Runs of each pose; the least time counts.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Writes each pose's volume and contact count to this file.
    #[arg(long)]
    dump: Option<PathBuf>,
    /// How far the spheres may reach past each surface, in voxels (`BuildOptions::surface_offset`).
    #[arg(long, default_value_t = BuildOptions::DEFAULT_SURFACE_OFFSET)]
    surface_offset: f32,
    /// Answer the poses in order with the temporal-coherence query (`CoherentOverlap`, one neighbour
    /// list kept along the trajectory); every pose runs once (a repeat would find its list ready).
    #[arg(long)]
    coherent: bool,
    /// Time the gem's tree against the bunny's signed distance grid (`overlap_field`).
    #[arg(long, conflicts_with = "coherent")]
    field: bool,
    /// The neighbour list's skin in micrometres (default: `CoherentOverlap::skin_for` the two trees).
    #[arg(long, requires = "coherent")]
    skin_um: Option<f32>,
}

fn tree(mesh: &TriMesh, n: usize, name: &str, surface_offset: f32) -> InnerSphereTree {
    let file = format!("../../target/collette-bench/{name}-{n}-offset{surface_offset}.ist");
    let cache = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(file);
    if let Ok(t) = InnerSphereTree::load(&cache) {
        return t;
    }
    let (t, _) = build(mesh, &BuildOptions { surface_offset, ..BuildOptions::spheres(n) }, &mut |_| {})
        .expect("the scene meshes are valid");
    let _ = std::fs::create_dir_all(cache.parent().expect("cache has a folder"));
    let _ = t.save(&cache);
    t
}

/// The value at fraction `q` (0–1) of `sorted` (0 when it is empty).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted.get((sorted.len().saturating_sub(1) as f64 * q).round() as usize).copied().unwrap_or(0.0)
}

fn main() {
    let args = Args::parse();
    let (nt, nb) = (args.spheres.a, args.spheres.b);
    let bunny_mesh = load_bunny(default_bunny_path()).expect("bunny loads");
    let tool = tree(&brilliant_cut(collette::scene::TOOL_DIAMETER), nt, "gem", args.surface_offset);
    let bunny = tree(&bunny_mesh, nb, "bunny", args.surface_offset);
    let path = trajectory(&bunny_mesh);

    let mut coherent = args.coherent.then(|| {
        let skin = args.skin_um.map_or_else(|| CoherentOverlap::skin_for(&tool, &bunny), |um| um * 1e-6);
        CoherentOverlap::new(skin).unwrap_or_else(|e| {
            eprintln!("error: --skin-um: {e}");
            std::process::exit(2)
        })
    });
    let grid = args.field.then(|| {
        let started = Instant::now();
        let grid = SignedDistanceGrid::new(&bunny_mesh, BuildOptions::spheres(nb).resolution()).expect("bunny grid");
        let [x, y, z] = grid.dims();
        println!("bunny distance grid {x} × {y} × {z}, built in {:.1} s", started.elapsed().as_secs_f64());
        grid
    });
    let runs = if coherent.is_some() { 1 } else { args.runs.max(1) };
    let (mut volume_sum, mut most_candidates) = (0.0f64, (0, 0));
    let (mut reused, mut collecting) = (Vec::new(), Vec::new());
    let (mut collections, mut slowest_reuse) = (0, (0.0f64, 0usize, collette::OverlapResult::default(), (0, 0)));
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let mut times = Vec::with_capacity(path.len());
    let mut dump = String::new();
    let (mut checksum, mut worst) = (0.0f64, (0.0f64, 0usize, Default::default()));
    for (i, s) in path.iter().enumerate() {
        let mut best = f64::MAX;
        let mut result = Default::default();
        for _ in 0..runs {
            let t0 = Instant::now();
            result = match (&mut coherent, &grid) {
                (Some(list), _) => list.query(&tool, &s.tool, &bunny, &Pose::IDENTITY, &mut ws, &mut set),
                (None, Some(grid)) => overlap_field(&tool, &s.tool, &bunny, grid, &Pose::IDENTITY, &mut ws, &mut set),
                (None, None) => {
                    overlap_budgeted(&tool, &s.tool, &bunny, &Pose::IDENTITY, Budget::Unlimited, &mut ws, &mut set)
                }
            };
            best = best.min(t0.elapsed().as_secs_f64() * 1e6);
        }
        volume_sum += result.total_volume as f64 * 1e6;
        if let Some(list) = &coherent {
            let (p, n) = list.len();
            most_candidates = (most_candidates.0.max(p), most_candidates.1.max(n));
            let collected = list.stats().collections > collections;
            collections = list.stats().collections;
            if collected {
                collecting.push(best)
            } else {
                reused.push(best)
            }
            if !collected && best > slowest_reuse.0 {
                slowest_reuse = (best, i, result, list.len());
            }
        }
        times.push(best);
        checksum += result.total_volume as f64 * 1e6 + set.len() as f64;
        if best > worst.0 {
            worst = (best, i, result);
        }
        if args.dump.is_some() {
            let _ = writeln!(dump, "{i} {:e} {}", result.total_volume, set.len());
        }
    }
    if let Some(p) = args.dump {
        std::fs::write(&p, dump).expect("dump written");
    }
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let at = |q: f64| quantile(&sorted, q);
    let total: f64 = times.iter().sum();
    println!(
        "{} poses, {nt}:{nb} spheres, {}least of {} runs: p50 {:.1} us, p99 {:.1} us, p99.9 {:.1} us, \
         max {:.1} us, mean {:.1} us",
        path.len(),
        if coherent.is_some() {
            "coherent, "
        } else if grid.is_some() {
            "against the bunny's distance grid, "
        } else {
            ""
        },
        runs,
        at(0.5),
        at(0.99),
        at(0.999),
        at(1.0),
        total / times.len() as f64
    );
    let (t, i, r): (f64, usize, collette::OverlapResult) = worst;
    println!(
        "slowest pose {i} (t = {:.3} s): {t:.1} us, {} node pairs, {} leaf pairs, {} aggregated",
        i as f64 / 1000.0,
        r.node_pairs,
        r.leaf_pairs,
        r.aggregated_pairs
    );
    println!("checksum {checksum:.6} (volumes alone {volume_sum:.6})");
    if let Some(list) = &coherent {
        for (name, mut v) in [("reusing the list", reused), ("collecting it", collecting)] {
            v.sort_by(f64::total_cmp);
            let q = |q: f64| quantile(&v, q);
            let over = v.iter().filter(|&&t| t > 100.0).count();
            println!(
                "  {name}: {} poses, p50 {:.1} us, p99 {:.1} us, max {:.1} us, {over} over 100 us",
                v.len(),
                q(0.5),
                q(0.99),
                q(1.0)
            );
        }
        let (t, i, r, (rows, nodes)) = slowest_reuse;
        println!(
            "  slowest pose reusing the list: {i}, {t:.1} us, {rows} candidate pairs and {nodes} nodes listed, {} leaf \
             pairs, {} aggregated, {} node pairs visited",
            r.leaf_pairs, r.aggregated_pairs, r.node_pairs
        );
        let st = list.stats();
        println!(
            "neighbour list: skin {:.1} um, collected {} times in {} queries ({:.1} %), {} overflows, at most {} \
             candidate pairs and {} nodes",
            list.skin() * 1e6,
            st.collections,
            st.queries,
            100.0 * st.collections as f64 / st.queries as f64,
            st.overflows,
            most_candidates.0,
            most_candidates.1
        );
    }
}
