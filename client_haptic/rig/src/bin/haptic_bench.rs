//! haptic-bench: the gemstone-over-bunny trajectory through the full loop (simulated device, haptic and
//! collision threads, collette's budgeted queries, forcecomp) for 35 s; per-100 ms window rates and
//! forces as CSV and a Fig. 9-style PNG, a summary line, and with `--json` a JSON object printed last.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Parser;
use collette::scene;
use forcecomp::Material;
use glam::Vec3;
use haptic_common::{Delegator, ForceTorque, Pose};
use haptic_rig::lockstep::Lockstep;
use haptic_rig::{CollisionConfig, HapticRig, ObjectSpec, Rendering, RigConfig, ToolSpec, bench};
use haptico::sim::{Keyframe, SimConfig, SimDevice, TargetPath};
use haptico::trace::{self, Trace, TraceDevice, TraceWriter};
use haptico::{Device, HapticConfig, HapticEvents, presets};

#[derive(Parser, Debug)]
#[command(
    about = "Runs the gemstone-over-bunny trajectory through the full haptic loop and measures it (paper Fig. 9)."
)]
struct Args {
    /// Seconds to run (the trajectory lasts 35 s).
    #[arg(long, default_value_t = 35.0)]
    seconds: f64,
    /// Device preset (part of its name): touch, omni, desktop, premium, falcon, omega, sigma, delta.
    #[arg(long, default_value = "premium")]
    device: String,
    /// Spheres in the gemstone tool's tree.
    #[arg(long, default_value_t = 500)]
    tool_spheres: usize,
    /// Spheres in the bunny's tree.
    #[arg(long, default_value_t = 10_000)]
    bunny_spheres: usize,
    /// Time budget of one collision step, µs.
    #[arg(long, default_value_t = 500)]
    budget_us: u32,
    /// Haptic and collision rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    rate_hz: f32,
    /// Random extra delay of the simulated device's reads, µs.
    #[arg(long, default_value_t = 0)]
    jitter_us: u32,
    /// Directory for windows.csv and haptic_bench.png.
    #[arg(long, default_value = "target/haptic-bench")]
    out_dir: PathBuf,
    /// Also write the PNG here (e.g. docs/img/haptic_bench.png).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Run both threads under SCHED_FIFO (haptic at this priority, collision one below); needs root or
    /// an rtprio limit, silently normal otherwise (the summary says which).
    #[arg(long)]
    realtime: Option<i32>,
    /// Spin instead of sleeping for the last part of each period, µs (both threads).
    #[arg(long, default_value_t = 300)]
    spin_us: u32,
    /// Force rendering: "volumetric" (the gemstone's inner spheres against the bunny's, coupled, 6-DOF)
    /// or "proxy" (3-DOF god-object: the gemstone's centre as a point tip held on the bunny's spheres).
    #[arg(long, default_value = "volumetric")]
    rendering: String,
    /// Measure the gemstone against the bunny's surface (a signed distance grid as fine as the bunny's
    /// packing grid, `collette::overlap_field`) instead of the bunny's tree: the volume that follows
    /// the real intersection for a tool this much smaller than the object (docs/collette.md).
    #[arg(long)]
    surface: bool,
    /// With `--surface`: the gemstone's surface split to edges of at most this many millimetres (its
    /// shell), measured instead of its spheres against the bunny's grid (`collette::overlap_shell`);
    /// 0: its spheres.
    #[arg(long, default_value_t = 0.0)]
    shell_edge_mm: f32,
    /// With `--shell-edge-mm`: the gemstone's grid (64 voxels) and the bunny's shell (edges as long) too,
    /// so that both surfaces are measured (`collette::overlap_surfaces_budgeted`).
    #[arg(long)]
    both_surfaces: bool,
    /// Scatter this many small objects (1.2 cm balls and boxes of 300 spheres) around the bunny, in the
    /// tool's way: a whole scene for the collision thread's broad phase (at most 255 beside the bunny).
    #[arg(long, default_value_t = 0)]
    objects: usize,
    /// Query every object every collision step (no broad phase), to compare.
    #[arg(long)]
    no_broad_phase: bool,
    /// Print the summary as one JSON object, last.
    #[arg(long)]
    json: bool,
    /// Record the device's every tick (state read, force commanded) to this trace file (`haptico trace
    /// v2`, docs/haptics.md).
    #[arg(long)]
    record: Option<PathBuf>,
    /// Drive the loop with a recorded trace instead of the scripted hand (at most `--seconds` of it).
    /// With `--lockstep`, the forces are compared with the recorded ones, tick by tick.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Run both stages in one thread on simulated time, exact queries every tick (deterministic: a
    /// replay of a lockstep recording gives the recorded forces to the bit). Prints forces, no rates.
    #[arg(long)]
    lockstep: bool,
}

/// Errors end the program on one line (`error: what: why`), never with a backtrace, even with
/// `RUST_BACKTRACE` set.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<()> {
    // Log lines (none by default) to stderr, chosen with RUST_LOG like every binary of the workspace.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .try_init();
    let args = Args::parse();
    let specs =
        presets::by_name(&args.device).with_context(|| format!("no device preset matches {:?}", args.device))?;

    if args.shell_edge_mm != 0.0 && !(args.surface && (0.2..=10.0).contains(&args.shell_edge_mm)) {
        anyhow::bail!("--shell-edge-mm takes 0.2 to 10 (mm) and needs --surface, not {}", args.shell_edge_mm);
    }
    if args.both_surfaces && args.shell_edge_mm == 0.0 {
        anyhow::bail!("--both-surfaces needs --shell-edge-mm (and --surface)");
    }
    let locked = args.realtime.is_some() && haptico::timing::lock_memory();
    let started = Instant::now();
    let bunny_mesh = scene::load_bunny(scene::default_bunny_path()).context("loading the bunny")?;
    let gem_mesh = scene::brilliant_cut(scene::TOOL_DIAMETER);
    let (bunny, _) = collette::build(&bunny_mesh, &collette::BuildOptions::spheres(args.bunny_spheres), &mut |_| {})
        .context("building the bunny's tree")?;
    let (gem, _) = collette::build(&gem_mesh, &collette::BuildOptions::spheres(args.tool_spheres), &mut |_| {})
        .context("building the gemstone's tree")?;
    let surface = match args.surface {
        true => {
            let resolution = collette::BuildOptions::spheres(args.bunny_spheres).resolution();
            let grid =
                collette::SignedDistanceGrid::new(&bunny_mesh, resolution).context("the bunny's distance grid")?;
            Some(Arc::new(grid))
        }
        false => None,
    };
    let edge_m = args.shell_edge_mm * 1e-3;
    let shell_of = |mesh, what| match edge_m > 0.0 {
        true => collette::SurfaceShell::new(mesh, edge_m).map(Arc::new).map(Some).context(what),
        false => Ok(None),
    };
    let gem_shell = shell_of(&gem_mesh, "the gemstone's shell")?;
    let (gem_grid, bunny_shell) = match args.both_surfaces {
        true => (
            Some(Arc::new(collette::SignedDistanceGrid::new(&gem_mesh, 64).context("the gemstone's grid")?)),
            shell_of(&bunny_mesh, "the bunny's shell")?,
        ),
        false => (None, None),
    };
    eprintln!(
        "haptic-bench: trees built in {:.1} s ({} bunny spheres, {} tool spheres{}{}{})",
        started.elapsed().as_secs_f64(),
        bunny.spheres().len(),
        gem.spheres().len(),
        if surface.is_some() { ", the bunny's distance grid" } else { "" },
        gem_shell
            .as_ref()
            .map_or(String::new(), |s| format!(", the gemstone's shell of {} triangles", s.triangles().len())),
        bunny_shell
            .as_ref()
            .map_or(String::new(), |s| format!(", the bunny's of {} and the gemstone's grid", s.triangles().len())),
    );

    // The hand follows the scripted tool path (or a recorded trace); the device frame is the scene
    // frame (metres).
    let replay = match &args.replay {
        Some(file) => Some(trace::load_trace(file).with_context(|| format!("reading the trace {}", file.display()))?),
        None => None,
    };
    let device: Box<dyn Device> = match &replay {
        Some(t) => Box::new(TraceDevice::new(specs.clone(), t.states.clone(), false).context("the trace")?),
        None => {
            let path = scene::trajectory(&bunny_mesh);
            let keyframes: Vec<Keyframe> = path.iter().map(|s| Keyframe { t_s: s.time_s, pose: s.tool }).collect();
            Box::new(SimDevice::new(
                SimConfig { jitter_us: args.jitter_us, ..SimConfig::new(specs.clone()) },
                TargetPath::Keyframes(keyframes),
            ))
        }
    };
    let (device, recording): (Box<dyn Device>, _) = match &args.record {
        Some(file) => {
            let (device, writer) = trace::record(device, file).context("recording")?;
            (Box::new(device), Some(writer))
        }
        None => (device, None),
    };
    let ticks = (args.seconds * args.rate_hz as f64) as usize + 1000;
    let config = RigConfig {
        haptic: HapticConfig {
            rate_hz: args.rate_hz,
            timing_capacity: ticks,
            realtime_priority: args.realtime,
            spin_margin_us: args.spin_us,
            ..HapticConfig::default()
        },
        collision: CollisionConfig {
            rate_hz: args.rate_hz,
            budget_us: args.budget_us,
            timing_capacity: ticks,
            realtime_priority: args.realtime.map(|p| (p - 1).max(1)),
            spin_margin_us: args.spin_us,
            broad_phase: !args.no_broad_phase,
            ..CollisionConfig::default()
        },
        force_sample_capacity: ticks,
        rendering: match args.rendering.as_str() {
            "volumetric" => Rendering::Coupled,
            "proxy" => Rendering::Proxy,
            other => anyhow::bail!("--rendering must be volumetric or proxy, not {other:?}"),
        },
        ..RigConfig::default()
    };
    // Stiff enough for newtons at a few millimetres, soft enough that the deep stretch really goes deep.
    let mut tool = ToolSpec::new(
        Arc::new(gem),
        Material { stiffness_n_per_m3: 5e8, damping_ns_per_m: 4.0, friction: 0.3, texture: None },
    );
    if let Some(shell) = gem_shell {
        tool = tool.with_shell(shell);
    }
    if let Some(grid) = gem_grid {
        tool = tool.with_surface(grid);
    }
    let surface = BunnySurface { grid: surface, shell: bunny_shell };
    let bunny_material = Material { stiffness_n_per_m3: 5e7, damping_ns_per_m: 4.0, friction: 0.3, texture: None };
    let bunny = ObjectSpec { id: 1, tree: Arc::new(bunny), pose: Pose::IDENTITY, material: bunny_material };
    let scattered = scatter(args.objects, &bunny_mesh, &bunny_material)?;
    if args.lockstep {
        return lockstep(&args, device, tool, (bunny, surface, scattered), &config, replay.as_ref(), recording);
    }
    let rig = HapticRig::start(device, tool, config, HapticEvents::default(), Delegator::new())?;
    let id = bunny.id;
    rig.add_object(bunny)?;
    for object in scattered {
        rig.add_object(object)?;
    }
    rig.set_surface(id, surface.grid)?;
    rig.set_object_shell(id, surface.shell)?;

    let mut haptic = Vec::with_capacity(ticks);
    let mut collision = Vec::with_capacity(ticks);
    let mut forces = Vec::with_capacity(ticks);
    let steal_before = steal_ms();
    let clock = rig.clock();
    let mut steal_samples: Vec<(u64, u64)> = Vec::with_capacity(1000);
    let run_start = Instant::now();
    while run_start.elapsed() < Duration::from_secs_f64(args.seconds) {
        if let Some(st) = steal_ms() {
            steal_samples.push((clock.now_us(), st));
        }
        std::thread::sleep(Duration::from_millis(50));
        rig.drain_haptic_timings(&mut haptic);
        rig.drain_collision_timings(&mut collision);
        rig.drain_force_samples(&mut forces);
        rig.collect_garbage();
    }
    let steal = steal_ms().zip(steal_before).map(|(after, before)| after.saturating_sub(before));
    let telemetry = rig.telemetry();
    let haptic_telemetry = rig.haptic_telemetry();
    rig.drain_haptic_timings(&mut haptic);
    rig.drain_collision_timings(&mut collision);
    rig.drain_force_samples(&mut forces);
    rig.stop();
    if let Some(writer) = recording {
        say_recorded(writer)?;
    }

    let period_us = (1e6 / args.rate_hz as f64).round() as u64;
    let mut windows = bench::windows(&haptic, &collision, &forces, 100_000, period_us);
    bench::add_steal(&mut windows, &haptic, &steal_samples, 100_000, period_us);
    let s = bench::summary(&windows, &haptic, &collision, &forces, period_us as u32);
    let costs = bench::step_costs(&collision);
    let nominal = args.rate_hz as f64;
    let low_haptic = windows.iter().filter(|w| w.haptic_hz < nominal).count();
    let low_collision = windows.iter().filter(|w| w.collision_hz < nominal).count();
    let stalls = haptic.iter().filter(|t| t.period_us as u64 > 5 * period_us).count();
    let low_without_steal =
        windows.iter().filter(|w| (w.haptic_hz < nominal || w.collision_hz < nominal) && w.steal_ms == 0).count();

    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("creating {}", args.out_dir.display()))?;
    let csv_path = args.out_dir.join("windows.csv");
    let mut csv = std::io::BufWriter::new(std::fs::File::create(&csv_path)?);
    bench::write_csv(&mut csv, &windows)?;
    drop(csv);
    let title = format!("{} on the gemstone-over-bunny path, {} rendering: 100 ms windows", specs.name, args.rendering);
    let png_path = args.out_dir.join("haptic_bench.png");
    bench::plot(&png_path, &windows, &title).map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    if let Some(p) = &args.png {
        std::fs::copy(&png_path, p).with_context(|| format!("copying the plot to {}", p.display()))?;
    }

    println!(
        "haptic-bench: {} windows of 100 ms; min haptic {:.0} Hz, min collision {:.0} Hz; windows below {:.0} Hz: haptic {}, collision {} ({} of them without hypervisor steal near them); haptic stalls > 5 periods {}; CPU time stolen by the hypervisor {}; haptic period jitter p50 {} us, p99 {} us, max {} us; collision jitter p50 {} us, p99 {} us; budget hits {}; collision step p50 {} us, p99 {} us (broad phase p99 {:.1} us, {:.1} % of the work; {:.1} pairs queried and {:.1} skipped a step, {} objects{}); max |F| {:.2} N (peak {:.2}), max |tau| {:.3} N.m, max |dF| per tick {:.3} N; skipped ticks {}; real-time scheduling {}, memory locked {}; safety {:?}; CSV {}, PNG {}",
        s.windows,
        s.min_haptic_hz,
        s.min_collision_hz,
        nominal,
        low_haptic,
        low_collision,
        low_without_steal,
        stalls,
        steal.map_or("unknown".to_string(), |ms| format!("{ms} ms (all CPUs)")),
        s.haptic.jitter_p50_us,
        s.haptic.jitter_p99_us,
        s.haptic.jitter_max_us,
        s.collision.jitter_p50_us,
        s.collision.jitter_p99_us,
        s.budget_hits,
        costs.work_p50_us,
        costs.work_p99_us,
        costs.broad_p99_us,
        costs.broad_share * 100.0,
        costs.queried_mean,
        costs.culled_mean,
        args.objects + 1,
        if args.no_broad_phase { ", no broad phase" } else { "" },
        s.max_force_n,
        specs.peak_force_n,
        s.max_torque_nm,
        s.max_force_step_n,
        haptic_telemetry.skipped_ticks,
        if haptic_telemetry.realtime { "on" } else { "off" },
        if locked { "yes" } else { "no" },
        telemetry.safety,
        csv_path.display(),
        png_path.display(),
    );
    if args.json {
        let json = serde_json::json!({
            "min_haptic_hz": s.min_haptic_hz,
            "min_collision_hz": s.min_collision_hz,
            "jitter_p50_us": s.haptic.jitter_p50_us,
            "jitter_p99_us": s.haptic.jitter_p99_us,
            "jitter_max_us": s.haptic.jitter_max_us,
            "collision_jitter_p50_us": s.collision.jitter_p50_us,
            "collision_jitter_p99_us": s.collision.jitter_p99_us,
            "budget_hits": s.budget_hits,
            "collision_step_p50_us": costs.work_p50_us,
            "collision_step_p99_us": costs.work_p99_us,
            "broad_phase_p99_us": costs.broad_p99_us,
            "broad_phase_share": costs.broad_share,
            "pairs_queried_mean": costs.queried_mean,
            "pairs_culled_mean": costs.culled_mean,
            "objects": args.objects + 1,
            "broad_phase": !args.no_broad_phase,
            "max_force_n": s.max_force_n,
            "max_torque_nm": s.max_torque_nm,
            "max_force_step_n": s.max_force_step_n,
            "windows": s.windows,
            "device": specs.name,
            "rendering": args.rendering,
            "surface": args.surface,
            "shell_edge_mm": args.shell_edge_mm,
            "both_surfaces": args.both_surfaces,
            "realtime": haptic_telemetry.realtime,
            "memory_locked": locked,
            "windows_below_target_haptic": low_haptic,
            "windows_below_target_collision": low_collision,
            "haptic_stalls": stalls,
            "windows_below_target_without_steal": low_without_steal,
            "steal_ms": steal,
            "seconds": args.seconds,
        });
        println!("{json}");
    }
    Ok(())
}

/// The bunny's surface grid (`--surface`) and shell (`--both-surfaces`).
struct BunnySurface {
    grid: Option<Arc<collette::SignedDistanceGrid>>,
    shell: Option<Arc<collette::SurfaceShell>>,
}

/// The run on simulated time (`--lockstep`): every tick of the scripted path, or of the replayed
/// trace at its own times; with a replay of a trace holding commands, how many ticks' forces are the
/// recorded ones to the bit.
fn lockstep(
    args: &Args,
    device: Box<dyn Device>,
    tool: ToolSpec,
    (bunny, surface, scattered): (ObjectSpec, BunnySurface, Vec<ObjectSpec>),
    config: &RigConfig,
    replay: Option<&Trace>,
    recording: Option<TraceWriter>,
) -> anyhow::Result<()> {
    let period_us = (1e6 / args.rate_hz as f64).round() as u64;
    let last_us = (args.seconds * 1e6) as u64;
    let times: Vec<u64> = match replay {
        Some(t) => {
            let first = t.states[0].timestamp_us;
            t.states.iter().map(|s| s.timestamp_us).take_while(|&t| t - first < last_us).collect()
        }
        None => (0..last_us / period_us).map(|i| i * period_us).collect(),
    };
    let mut rig = Lockstep::new(device, tool, config, 1, None)?;
    let id = bunny.id;
    rig.add_object(bunny)?;
    for object in scattered {
        rig.add_object(object)?;
    }
    rig.set_surface(id, surface.grid)?;
    rig.set_object_shell(id, surface.shell)?;
    let started = Instant::now();
    let forces: Vec<ForceTorque> = times.iter().map(|&t| rig.tick(t)).collect();
    let elapsed = started.elapsed();
    let safety = rig.telemetry().safety;
    drop(rig);
    if let Some(writer) = recording {
        say_recorded(writer)?;
    }
    let max_f = forces.iter().map(|f| f.force.length()).fold(0.0f32, f32::max);
    let max_tau = forces.iter().map(|f| f.torque.length()).fold(0.0f32, f32::max);
    let in_contact = forces.iter().filter(|f| f.force != Vec3::ZERO).count();
    println!(
        "haptic-bench --lockstep: {} ticks in {:.2} s ({:.0} us per tick, exact queries); ticks with a force {}; max |F| {:.2} N, max |tau| {:.3} N.m; safety {:?}",
        forces.len(),
        elapsed.as_secs_f64(),
        elapsed.as_secs_f64() * 1e6 / forces.len().max(1) as f64,
        in_contact,
        max_f,
        max_tau,
        safety
    );
    let compared = replay.and_then(|t| t.commands.as_deref()).map(|recorded| {
        let same = forces.iter().zip(recorded).filter(|(a, b)| a.to_bits() == b.to_bits()).count();
        let worst = forces.iter().zip(recorded).map(|(a, b)| (a.force - b.force).length()).fold(0.0f32, f32::max);
        println!(
            "replay: {same} of {} ticks' forces are the recorded ones to the bit; largest force difference {worst:.3e} N",
            forces.len()
        );
        (same, worst)
    });
    if args.json {
        let json = serde_json::json!({
            "lockstep": true,
            "rendering": args.rendering,
            "surface": args.surface,
            "shell_edge_mm": args.shell_edge_mm,
            "both_surfaces": args.both_surfaces,
            "ticks": forces.len(),
            "seconds_wall": elapsed.as_secs_f64(),
            "ticks_with_force": in_contact,
            "max_force_n": max_f,
            "max_torque_nm": max_tau,
            "replay_identical_ticks": compared.map(|c| c.0),
            "replay_max_force_difference_n": compared.map(|c| c.1),
        });
        println!("{json}");
    }
    Ok(())
}

/// `n` small objects (balls and boxes of 1.2 cm, 300 spheres each, two trees shared by all) scattered
/// at random (a fixed seed) in the bunny's box grown by 2 cm: in the tool's way along the path.
fn scatter(n: usize, bunny: &collette::TriMesh, material: &Material) -> anyhow::Result<Vec<ObjectSpec>> {
    if n == 0 {
        return Ok(Vec::new());
    }
    anyhow::ensure!(n < haptic_rig::MAX_OBJECTS, "--objects: at most {} beside the bunny", haptic_rig::MAX_OBJECTS - 1);
    let shapes = [collette::shape::uv_sphere_buffers(0.006, 12, 16), collette::shape::box_buffers(Vec3::splat(0.006))];
    let mut trees = Vec::new();
    for (v, t) in shapes {
        let mesh = collette::TriMesh::new(v, t).context("a scattered object's mesh")?;
        let (tree, _) = collette::build(&mesh, &collette::BuildOptions::spheres(300), &mut |_| {})
            .context("a scattered object's tree")?;
        trees.push(Arc::new(tree));
    }
    let area = bunny.aabb();
    let (low, size) = (area.min - Vec3::splat(0.02), area.extents() + Vec3::splat(0.04));
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0x2545_f491);
    let mut roll = || rand::Rng::random::<f32>(&mut rng);
    Ok((0..n)
        .map(|i| {
            let at = low + size * Vec3::new(roll(), roll(), roll());
            let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, roll() * 3.0, roll() * 3.0, roll() * 3.0);
            ObjectSpec { id: 2 + i as u32, tree: trees[i % 2].clone(), pose: Pose::new(at, turn), material: *material }
        })
        .collect())
}

/// Closes a recording and says what it wrote.
fn say_recorded(writer: TraceWriter) -> anyhow::Result<()> {
    let path = writer.path().to_owned();
    let stats = writer.finish().context("recording")?;
    eprintln!("haptic-bench: recorded {} ticks to {} ({} lost)", stats.written, path.display(), stats.dropped);
    Ok(())
}

/// CPU time the hypervisor took from this machine so far (Linux `/proc/stat`, "steal"), ms over all CPUs.
fn steal_ms() -> Option<u64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let line = stat.lines().find(|l| l.starts_with("cpu "))?;
    let jiffies: u64 = line.split_whitespace().nth(8)?.parse().ok()?;
    Some(jiffies * 10) // USER_HZ is 100 on Linux
}
