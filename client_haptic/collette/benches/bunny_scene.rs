//! The paper's benchmark scene: a 1 cm brilliant-cut gem exploring the 10 cm Stanford bunny along the
//! scripted 35 s / 1 kHz trajectory, against parry3d's triangle-mesh contact query on the same poses.
//!
//! `cargo bench -p collette_ist --bench bunny_scene` first prints (and writes to
//! `target/collette-bench/`) the table of build time, coverage and query time percentiles for each
//! sphere count (the exact aggregated query also with temporal coherence, `CoherentOverlap`, in a pass
//! of its own that takes every pose once, in order), then runs a few criterion micro-benchmarks.
//! Environment:
//! `COLLETTE_BENCH_SIZES` (default `1000,5000,10000,50000`; `TOOL:BUNNY`, e.g. `4000:20000`, gives the
//! two trees different counts), `COLLETTE_BENCH_BUDGET_US` (default 80),
//! `COLLETTE_BENCH_STRIDE` (use every n-th pose, default 1), `COLLETTE_BENCH_TABLE_ONLY` (skip criterion),
//! `COLLETTE_BENCH_SURFACE_OFFSET` (voxels the spheres reach past the surface; default
//! `BuildOptions::DEFAULT_SURFACE_OFFSET`, 0 for the inner packing).

use collette::scene::{
    Phase, SphereCounts, TrajectorySample, brilliant_cut, default_bunny_path, load_bunny, trajectory,
    write_trajectory_csv,
};
use collette::{
    Budget, BuildOptions, CoherentOverlap, ContactSet, InnerSphereTree, Pose, QueryWorkspace, TriMesh, build, overlap,
    overlap_budgeted,
};
use criterion::Criterion;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// The given percentiles (0–1; 1 is the max) of a list of durations in microseconds.
fn percentiles(mut us: Vec<f64>, at: [f64; 3]) -> [f64; 3] {
    if us.is_empty() {
        return [f64::NAN; 3];
    }
    us.sort_by(f64::total_cmp);
    at.map(|p| us[((us.len() - 1) as f64 * p).round() as usize])
}

/// p50, p99 and max.
fn stats(us: Vec<f64>) -> [f64; 3] {
    percentiles(us, [0.5, 0.99, 1.0])
}

/// p99, p99.9 and max.
fn tail(us: Vec<f64>) -> [f64; 3] {
    percentiles(us, [0.99, 0.999, 1.0])
}

fn to_parry_pose(p: &Pose) -> parry3d::math::Pose {
    let (t, q) = (p.translation, p.rotation);
    parry3d::math::Pose::from_parts(
        parry3d::math::Vector::new(t.x, t.y, t.z),
        parry3d::math::Rotation::from_xyzw(q.x, q.y, q.z, q.w),
    )
}

struct Built {
    tree: InnerSphereTree,
    seconds: f64,
    coverage: f64,
}

fn build_tree(mesh: &TriMesh, n: usize) -> Built {
    let surface_offset = env_or("COLLETTE_BENCH_SURFACE_OFFSET", BuildOptions::DEFAULT_SURFACE_OFFSET);
    let options = BuildOptions { surface_offset, ..BuildOptions::spheres(n) };
    let (tree, report) = build(mesh, &options, &mut |_| {}).expect("the scene meshes are valid");
    Built { tree, seconds: report.build_seconds, coverage: report.coverage }
}

struct QueryRun {
    exact: Vec<(f64, Phase)>,
    aggregated: Vec<f64>,
    budgeted: Vec<f64>,
    /// How long after its deadline each budgeted query returned, µs (0 when in time).
    overshoot: Vec<f64>,
    /// The least overshoot of each pose's budgeted query over three runs: what the query itself does,
    /// with the machine's interruptions (descheduling, hypervisor steal) mostly filtered out.
    overshoot_least: Vec<f64>,
    budget_error_deep: f64,
    budget_error_grazing: f64,
    max_pairs: u32,
    contact_fraction: f64,
    /// The exact aggregated query with temporal coherence ([`CoherentOverlap`]), every pose once in
    /// trajectory order in a pass of its own.
    coherent: Vec<f64>,
    /// Share of the coherent queries that collected their neighbour list anew.
    coherent_collections: f64,
    /// Largest relative difference between the coherent and the plain aggregated volume.
    coherent_volume_error: f64,
}

fn run_queries(
    bunny: &InnerSphereTree,
    tool: &InnerSphereTree,
    path: &[TrajectorySample],
    budget: Duration,
) -> QueryRun {
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    let (mut exact, mut budgeted) = (Vec::with_capacity(path.len()), Vec::with_capacity(path.len()));
    let mut aggregated = Vec::with_capacity(path.len());
    let mut overshoot = Vec::with_capacity(path.len());
    let mut overshoot_least = Vec::with_capacity(path.len());
    let mut volumes = Vec::with_capacity(path.len());
    let (mut max_pairs, mut touching) = (0u32, 0usize);
    // Per phase: summed absolute error of the budgeted volume and summed exact volume.
    let (mut deep_err, mut deep_vol, mut graze_err, mut graze_vol) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for s in path {
        let t0 = Instant::now();
        let full = overlap(tool, &s.tool, bunny, &Pose::IDENTITY, &mut ws, &mut set);
        exact.push((t0.elapsed().as_secs_f64() * 1e6, s.phase));
        max_pairs = max_pairs.max(full.leaf_pairs);
        touching += (full.total_volume > 0.0) as usize;
        let t2 = Instant::now();
        let exact = overlap_budgeted(tool, &s.tool, bunny, &Pose::IDENTITY, Budget::Unlimited, &mut ws, &mut set);
        aggregated.push(t2.elapsed().as_secs_f64() * 1e6);
        volumes.push(exact.total_volume);
        let t1 = Instant::now();
        let deadline = t1 + budget;
        let part =
            overlap_budgeted(tool, &s.tool, bunny, &Pose::IDENTITY, Budget::Deadline(deadline), &mut ws, &mut set);
        let t3 = Instant::now();
        budgeted.push((t3 - t1).as_secs_f64() * 1e6);
        overshoot.push(t3.saturating_duration_since(deadline).as_secs_f64() * 1e6);
        let mut least = t3.saturating_duration_since(deadline);
        for _ in 0..2 {
            let deadline = Instant::now() + budget;
            overlap_budgeted(tool, &s.tool, bunny, &Pose::IDENTITY, Budget::Deadline(deadline), &mut ws, &mut set);
            least = least.min(Instant::now().saturating_duration_since(deadline));
        }
        overshoot_least.push(least.as_secs_f64() * 1e6);
        if full.total_volume > 0.0 {
            // Volume-weighted: summed absolute error over summed exact volume of the phase.
            let e = (part.total_volume - full.total_volume).abs() as f64;
            let v = full.total_volume as f64;
            match s.phase {
                Phase::Deep => (deep_err, deep_vol) = (deep_err + e, deep_vol + v),
                Phase::Grazing => (graze_err, graze_vol) = (graze_err + e, graze_vol + v),
                Phase::Free => {}
            }
        }
    }
    // The coherent query keeps state from pose to pose: its own pass, each pose once, in order.
    let mut list = CoherentOverlap::new(CoherentOverlap::skin_for(tool, bunny)).expect("a valid skin");
    let mut coherent = Vec::with_capacity(path.len());
    let mut coherent_volume_error = 0.0f64;
    for (s, &plain) in path.iter().zip(&volumes) {
        let t0 = Instant::now();
        let r = list.query(tool, &s.tool, bunny, &Pose::IDENTITY, &mut ws, &mut set);
        coherent.push(t0.elapsed().as_secs_f64() * 1e6);
        if plain > 0.0 {
            coherent_volume_error = coherent_volume_error.max(((r.total_volume - plain) / plain).abs() as f64);
        }
    }
    let st = list.stats();
    QueryRun {
        coherent,
        coherent_collections: st.collections as f64 / st.queries as f64,
        coherent_volume_error,
        exact,
        aggregated,
        budgeted,
        overshoot,
        overshoot_least,
        budget_error_deep: if deep_vol > 0.0 { deep_err / deep_vol } else { 0.0 },
        budget_error_grazing: if graze_vol > 0.0 { graze_err / graze_vol } else { 0.0 },
        max_pairs,
        contact_fraction: touching as f64 / path.len() as f64,
    }
}

fn main() {
    // Each entry `N` (both trees) or `TOOL:BUNNY`.
    let sizes: Vec<SphereCounts> = std::env::var("COLLETTE_BENCH_SIZES")
        .unwrap_or_else(|_| "1000,5000,10000,50000".into())
        .split(',')
        .filter_map(|s| s.parse().ok())
        .collect();
    let budget = Duration::from_micros(env_or("COLLETTE_BENCH_BUDGET_US", 80));
    let stride: usize = env_or("COLLETTE_BENCH_STRIDE", 1).max(1);
    let out_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/collette-bench");
    std::fs::create_dir_all(&out_dir).expect("output directory");

    let bunny = load_bunny(default_bunny_path()).expect("bunny loads");
    let tool = brilliant_cut(collette::scene::TOOL_DIAMETER);
    let full_path = trajectory(&bunny);
    write_trajectory_csv(out_dir.join("bunny_trajectory.csv"), &full_path).expect("trajectory written");
    let path: Vec<TrajectorySample> = full_path.iter().step_by(stride).copied().collect();

    // parry3d: triangle mesh vs triangle mesh contact (deepest point pair), same poses.
    let (pb, pt) = (collette::packing::to_parry(&bunny), collette::packing::to_parry(&tool));
    let bunny_pose = to_parry_pose(&Pose::IDENTITY);
    let mut parry_us = Vec::with_capacity(path.len());
    let mut parry_hits = 0usize;
    for s in &path {
        let tp = to_parry_pose(&s.tool);
        let t0 = Instant::now();
        let c = parry3d::query::contact(&tp, &pt, &bunny_pose, &pb, 0.0).expect("trimesh-trimesh contact is supported");
        parry_us.push(t0.elapsed().as_secs_f64() * 1e6);
        parry_hits += c.is_some() as usize;
    }
    let parry = stats(parry_us);

    let mut table = String::new();
    let _ = writeln!(
        table,
        "bunny scene: {} poses (stride {stride}), budget {} us, parry3d trimesh contact p50/p99/max = {:.1}/{:.1}/{:.1} us (contact in {:.1} % of poses)\n",
        path.len(),
        budget.as_micros(),
        parry[0],
        parry[1],
        parry[2],
        100.0 * parry_hits as f64 / path.len() as f64
    );
    let _ = writeln!(
        table,
        "| spheres | bunny build s | bunny coverage | tool build s | tool coverage | every-pair p50 / p99 / max us | aggregated p50 / p99 / max us | budgeted p50 / p99 / max us | budget error grazing / deep (volume-weighted) | deadline overshoot p99 / p99.9 / max us | least of 3 runs per pose: p99 / p99.9 / max us | max pairs | parry/aggregated p50 | parry/aggregated p99 | coherent exact p50 / p99 / max us | coherent: lists collected, largest volume difference | parry/coherent p99 |"
    );
    let _ = writeln!(table, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut phases = String::new();
    let _ = writeln!(
        phases,
        "\n| spheres | phase | every-pair p50 / p99 / max us | aggregated p50 / p99 / max us |\n|---|---|---|---|"
    );
    let mut json = Vec::new();
    for &counts in &sizes {
        let (nt, nb, n) = (counts.a, counts.b, counts.to_string());
        let b = build_tree(&bunny, nb);
        let t = build_tree(&tool, nt);
        let run = run_queries(&b.tree, &t.tree, &path, budget);
        let exact = stats(run.exact.iter().map(|e| e.0).collect());
        let budgeted = stats(run.budgeted.clone());
        let aggregated = stats(run.aggregated.clone());
        let overshoot = tail(run.overshoot.clone());
        let least = tail(run.overshoot_least.clone());
        let coherent = stats(run.coherent.clone());
        let _ = writeln!(
            table,
            "| {n} | {:.2} | {:.1} % | {:.2} | {:.1} % | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} | {:.1} % / {:.1} % | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} | {} | {:.2} | {:.2} | {:.1} / {:.1} / {:.1} | {:.1} % of poses, {:.1e} | {:.2} |",
            b.seconds,
            b.coverage * 100.0,
            t.seconds,
            t.coverage * 100.0,
            exact[0],
            exact[1],
            exact[2],
            aggregated[0],
            aggregated[1],
            aggregated[2],
            budgeted[0],
            budgeted[1],
            budgeted[2],
            run.budget_error_grazing * 100.0,
            run.budget_error_deep * 100.0,
            overshoot[0],
            overshoot[1],
            overshoot[2],
            least[0],
            least[1],
            least[2],
            run.max_pairs,
            parry[0] / aggregated[0],
            parry[1] / aggregated[1],
            coherent[0],
            coherent[1],
            coherent[2],
            run.coherent_collections * 100.0,
            run.coherent_volume_error,
            parry[1] / coherent[1]
        );
        for phase in [Phase::Free, Phase::Grazing, Phase::Deep] {
            let p = stats(run.exact.iter().filter(|e| e.1 == phase).map(|e| e.0).collect());
            let q =
                stats(run.exact.iter().zip(&run.aggregated).filter(|(e, _)| e.1 == phase).map(|(_, a)| *a).collect());
            let _ = writeln!(
                phases,
                "| {n} | {} | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} |",
                phase.as_str(),
                p[0],
                p[1],
                p[2],
                q[0],
                q[1],
                q[2]
            );
        }
        json.push(serde_json::json!({
            "spheres": n, "tool_spheres": nt, "bunny_spheres": nb, "bunny_build_seconds": b.seconds, "bunny_coverage": b.coverage,
            "tool_build_seconds": t.seconds, "tool_coverage": t.coverage,
            "every_pair_us": exact, "aggregated_us": aggregated, "budgeted_us": budgeted, "overshoot_p99_p999_max_us": overshoot, "overshoot_least_of_3_p99_p999_max_us": least, "budget_us": budget.as_micros() as u64,
            "deep_budget_volume_weighted_error": run.budget_error_deep, "grazing_budget_volume_weighted_error": run.budget_error_grazing, "max_leaf_pairs": run.max_pairs,
            "contact_fraction": run.contact_fraction, "parry_us": parry,
            "coherent_us": coherent, "coherent_collections": run.coherent_collections, "coherent_volume_error": run.coherent_volume_error,
        }));
        eprintln!("{n} spheres done");
    }
    table.push_str(&phases);
    println!("{table}");
    std::fs::write(out_dir.join("bench_table.md"), &table).expect("table written");
    std::fs::write(out_dir.join("bench_results.json"), serde_json::to_string_pretty(&json).unwrap_or_default())
        .expect("json written");

    if std::env::var_os("COLLETTE_BENCH_TABLE_ONLY").is_some() {
        return;
    }
    let mut c = Criterion::default().configure_from_args().measurement_time(Duration::from_secs(3)).sample_size(30);
    let b = build_tree(&bunny, 10_000).tree;
    let t = build_tree(&tool, 10_000).tree;
    let mut ws = QueryWorkspace::new();
    let mut set = ContactSet::new();
    for phase in [Phase::Grazing, Phase::Deep] {
        let pose = full_path.iter().filter(|s| s.phase == phase).nth(3000).map_or(Pose::IDENTITY, |s| s.tool);
        c.bench_function(&format!("overlap_10k_{}", phase.as_str()), |bench| {
            bench.iter(|| overlap(&t, &pose, &b, &Pose::IDENTITY, &mut ws, &mut set).total_volume)
        });
    }
    c.bench_function("build_bunny_1k", |bench| {
        bench.iter(|| build(&bunny, &BuildOptions::spheres(1000), &mut |_| {}).map(|r| r.1.spheres))
    });
    c.final_summary();
}
