//! Feels every copy of each artifact for the given seeds through the real haptic loop (sim device) and
//! prints what touch found next to the truth: the figures behind the touch bot's thresholds, and how
//! often it misjudges a copy when felt again and again.
//!
//!     cargo run --release -p client_haptic --no-default-features --example feel_copies -- 3 5 7
//!     cargo run --release -p client_haptic --no-default-features --example feel_copies -- \
//!         --heist --kind idol --real --repeat 16 10
//!
//! `--lockstep` steps the same rig in simulated time on one thread (as the touch tests do for most
//! copies): as fast as the machine computes it, the same on every run, no real-time rates.

use clap::Parser;
use client_haptic::cli::KindArg;
use client_haptic::explore::feel;
use client_haptic::haptics::{HapticsSettings, RenderingChoice};
use client_haptic::touch_bench::{LockstepHaptics, RealTimeHaptics, TouchBench};
use heist_shared::artifact::{ArtifactKind, build_mesh, copy_mesh_seed, generate_copies, target_seed};
use heist_shared::level::Level;
use heist_shared::protocol::{ItemId, WorkbenchCopy};

#[derive(Parser)]
struct Args {
    /// Only this kind.
    #[arg(long, value_enum)]
    kind: Option<KindArg>,
    /// Only the real one of each kind.
    #[arg(long)]
    real: bool,
    /// The copies of the heist with each seed on the shipped museum (as the server makes them), instead
    /// of the copies generated from the seed itself.
    #[arg(long)]
    heist: bool,
    /// How forces are rendered (auto: the 3-DOF proxy for the default Phantom Desktop preset).
    #[arg(long, value_enum, default_value_t = RenderingChoice::Auto)]
    rendering: RenderingChoice,
    /// Device preset the sim device copies (default the Phantom Desktop).
    #[arg(long)]
    preset: Option<String>,
    /// Step the rig in simulated time on one thread instead of running it in real time.
    #[arg(long)]
    lockstep: bool,
    /// Feel each copy this many times.
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Seeds whose copies are felt.
    #[arg(required = true)]
    seeds: Vec<u64>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let settings =
        HapticsSettings { rendering: args.rendering, preset: args.preset.clone(), ..HapticsSettings::default() };
    if args.lockstep {
        return feel_all(&mut LockstepHaptics::start(settings)?, &args);
    }
    let mut h = RealTimeHaptics::start(settings)?;
    let felt = feel_all(&mut h, &args);
    h.stop();
    felt
}

/// Feels the copies `args` name on `bench`, printing a CSV row each.
fn feel_all(bench: &mut impl TouchBench, args: &Args) -> anyhow::Result<()> {
    let museum = Level::museum();
    println!(
        "kind,seed,count,material,felt_count,felt_material,stiffness_n_per_m,pressure_n_per_m2,friction,\
         ridge_mm,ridge_strength,stroke_contact,attempts,presses,right"
    );
    let (mut item, mut felt, mut wrong) = (0, 0, 0);
    for &seed in &args.seeds {
        for kind in
            ArtifactKind::ALL.into_iter().filter(|k| args.kind.is_none_or(|only| ArtifactKind::from(only) == *k))
        {
            // A heist's copies of a kind: its target on the shipped museum, as the server sets it up.
            let target = museum.targets.iter().position(|t| t.kind == kind).filter(|_| args.heist);
            let (copies_seed, count) = match target {
                Some(t) => (target_seed(seed, t), museum.targets[t].copies),
                None => (seed, 3),
            };
            let (copies, real) = generate_copies(kind, copies_seed, count);
            for (c, t) in copies.iter().enumerate().filter(|(c, _)| !args.real || *c == real) {
                let mesh = build_mesh(t, if target.is_some() { copy_mesh_seed(copies_seed, c) } else { seed });
                for _ in 0..args.repeat {
                    item += 1;
                    let copy =
                        WorkbenchCopy { item: ItemId(item), mesh: mesh.clone(), material: t.material.material() };
                    let f = feel(bench, &copy, kind).map_err(anyhow::Error::msg)?;
                    let right = f.feature_count == t.feature_count && f.material == t.material;
                    (felt, wrong) = (felt + 1, wrong + u32::from(!right));
                    if !right || f.presses > 1 || f.attempts > 1 {
                        let mm: Vec<String> = f.profile.iter().map(|r| format!("{:.1}", r * 1e3)).collect();
                        eprintln!("{kind:?} seed {seed}: {}; profile (mm) {}", f.describe(), mm.join(" "));
                    }
                    // The strongest repeat the strokes had, ridges or not (spacing, strength).
                    let (ridge_mm, ridge_strength) = f.ridges.map_or((0.0, 0.0), |(s, a)| (s * 1e3, a));
                    println!(
                        "{kind:?},{seed},{},{:?},{},{:?},{:.0},{:.0},{:.2},{ridge_mm:.1},{ridge_strength:.3},{:.2},{},{},{right}",
                        t.feature_count,
                        t.material,
                        f.feature_count,
                        f.material,
                        f.stiffness_n_per_m,
                        f.pressure_n_per_m2,
                        f.friction,
                        f.stroke_contact,
                        f.attempts,
                        f.presses,
                    );
                }
            }
        }
    }
    eprintln!("{wrong} of {felt} explorations misjudged their copy");
    Ok(())
}
