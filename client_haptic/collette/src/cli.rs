//! The `collette` command line: `build`, `info` and `render` (the binary's `main` only calls [`run`]).

use crate::{BuildOptions, BuildProgress, InnerSphereTree, TriMesh, build};
use anyhow::Context;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::time::Instant;

/// Inner Sphere Trees for volumetric collision detection.
#[derive(Debug, Parser)]
#[command(name = "collette", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Packs a closed OBJ mesh with spheres and writes an .ist file.
    Build {
        /// The closed triangle mesh (OBJ).
        mesh: PathBuf,
        /// Output .ist file.
        #[arg(short, long)]
        output: PathBuf,
        /// Number of spheres to pack (default 10,000).
        #[arg(long, conflicts_with = "coverage")]
        spheres: Option<usize>,
        /// Stop at this coverage (packed / mesh volume, 0..1) instead of a sphere count.
        #[arg(long)]
        coverage: Option<f32>,
        /// Voxels along the longest side of the mesh (default: from the target).
        #[arg(long)]
        resolution: Option<usize>,
        /// Smallest sphere radius, mesh units (default: a quarter voxel).
        #[arg(long)]
        min_radius: Option<f32>,
        /// How far spheres may reach past the surface, in voxels (0 keeps them all inside the mesh).
        #[arg(long, default_value_t = BuildOptions::DEFAULT_SURFACE_OFFSET)]
        surface_offset: f32,
        /// Multiply the mesh's coordinates by this factor first (e.g. 0.01 for centimetres to metres).
        #[arg(long, default_value_t = 1.0)]
        scale: f32,
        /// Print a JSON summary instead of text (no progress bar).
        #[arg(long)]
        json: bool,
    },
    /// Describes an .ist file.
    Info {
        /// The .ist file.
        file: PathBuf,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Draws the packing of an .ist file into a PNG (whole and cut-away views).
    Render {
        /// The .ist file.
        file: PathBuf,
        /// Output PNG.
        #[arg(short, long)]
        output: PathBuf,
        /// Height of each panel in pixels (the image is twice as wide).
        #[arg(long, default_value_t = 360)]
        size: u32,
        /// Camera yaw around the vertical axis, degrees.
        #[arg(long, default_value_t = 30.0)]
        yaw: f32,
        /// Camera pitch, degrees.
        #[arg(long, default_value_t = 15.0)]
        pitch: f32,
    },
}

/// Parses the process arguments and runs the command.
pub fn run() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Build { mesh, output, spheres, coverage, resolution, min_radius, surface_offset, scale, json } => {
            let raw = TriMesh::from_obj(&mesh).with_context(|| format!("loading {}", mesh.display()))?;
            let mesh_data = if scale == 1.0 { raw } else { raw.map_vertices(|v| v * scale)? };
            let options = BuildOptions {
                target_spheres: spheres,
                target_coverage: coverage,
                min_radius,
                grid_resolution: resolution,
                surface_offset,
                ..BuildOptions::default()
            };
            let bar = if json { indicatif::ProgressBar::hidden() } else { indicatif::ProgressBar::new(1000) };
            bar.set_style(
                indicatif::ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            let (tree, report) = build(&mesh_data, &options, &mut |p| match p {
                BuildProgress::DistanceField => bar.set_message("distance field"),
                BuildProgress::Packing { placed, target, coverage } => {
                    let by_count = if target == usize::MAX { 0.0 } else { placed as f64 / target as f64 };
                    let by_cov = options.target_coverage.map_or(0.0, |c| coverage / c as f64);
                    bar.set_position((by_count.max(by_cov).min(1.0) * 1000.0) as u64);
                    bar.set_message(format!("{placed} spheres, {:.1} % covered", coverage * 100.0));
                }
                BuildProgress::Hierarchy => bar.set_message("hierarchy"),
            })?;
            bar.finish_and_clear();
            tree.save(&output)?;
            let bytes = std::fs::metadata(&output).map(|m| m.len()).unwrap_or(0);
            if json {
                let v = serde_json::json!({
                    "mesh": mesh, "output": output, "spheres": report.spheres, "coverage": report.coverage,
                    "build_seconds": report.build_seconds, "mesh_volume": report.mesh_volume,
                    "packed_volume": report.packed_volume, "grid_resolution": report.grid_resolution,
                    "interior_voxels": report.interior_voxels, "nodes": tree.nodes().len(), "depth": tree.depth(),
                    "file_bytes": bytes,
                });
                println!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                println!("{} -> {} ({bytes} bytes)", mesh.display(), output.display());
                println!("  spheres        {}", report.spheres);
                println!(
                    "  coverage       {:.2} % of the exact mesh volume {:.6e}",
                    report.coverage * 100.0,
                    report.mesh_volume
                );
                println!(
                    "  build time     {:.3} s (grid {} voxels on the long side)",
                    report.build_seconds, report.grid_resolution
                );
                println!("  hierarchy      {} nodes, depth {}", tree.nodes().len(), tree.depth());
            }
        }
        Command::Info { file, json } => {
            let start = Instant::now();
            let tree = InnerSphereTree::load(&file)?;
            let load_ms = start.elapsed().as_secs_f64() * 1e3;
            let radii = tree.spheres().iter().map(|s| s.radius);
            let (rmin, rmax) = radii.fold((f32::INFINITY, 0.0f32), |(a, b), r| (a.min(r), b.max(r)));
            let root = tree.root().bound;
            let weights = tree.weights().iter();
            let (wmin, wmax) = weights.clone().fold((f32::INFINITY, 0.0f32), |(a, b), &w| (a.min(w), b.max(w)));
            let wmean = weights.sum::<f32>() / tree.weights().len().max(1) as f32;
            if json {
                let v = serde_json::json!({
                    "file": file, "spheres": tree.spheres().len(), "nodes": tree.nodes().len(), "depth": tree.depth(),
                    "mesh_volume": tree.mesh_volume(), "packed_volume": tree.packed_volume(), "coverage": tree.coverage(),
                    "mesh_share": tree.mesh_share(), "min_weight": wmin, "mean_weight": wmean, "max_weight": wmax,
                    "min_radius": rmin, "max_radius": rmax, "bound_center": root.center.to_array(),
                    "bound_radius": root.radius, "load_ms": load_ms,
                });
                println!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                println!("{}", file.display());
                println!("  spheres        {} (radius {rmin:.4e} .. {rmax:.4e})", tree.spheres().len());
                println!("  hierarchy      {} nodes, depth {}", tree.nodes().len(), tree.depth());
                println!("  coverage       {:.2} % of mesh volume {:.6e}", tree.coverage() * 100.0, tree.mesh_volume());
                println!(
                    "  weights        {wmin:.2} .. {wmax:.2} (mean {wmean:.2}): the spheres stand for {:.2} % of it",
                    100.0 * tree.mesh_share() / tree.mesh_volume().max(f32::MIN_POSITIVE)
                );
                println!("  bound          centre {:?}, radius {:.4e}", root.center.to_array(), root.radius);
                println!("  loaded in      {load_ms:.2} ms");
            }
        }
        Command::Render { file, output, size, yaw, pitch } => {
            let tree = InnerSphereTree::load(&file)?;
            let image =
                crate::render::render_packing(&tree, size.clamp(16, 4096), yaw.to_radians(), pitch.to_radians());
            image.write_png(&output).with_context(|| format!("writing {}", output.display()))?;
            println!("{} -> {} ({}x{})", file.display(), output.display(), image.width, image.height);
        }
    }
    Ok(())
}
