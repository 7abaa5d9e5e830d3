//! The paper's 1 cm gem pressed into a 20 cm slab's surface grid at 0.1, 1 and 5 mm: its inner spheres
//! against the grid (`overlap_field`) beside its surface against the grid (`overlap_shell`), the cost
//! the surface rendering adds, and both surfaces (`overlap_surfaces`: the gem's and the slab's shells
//! and grids), the rendering that stays right past the middle of thin parts (docs/collette.md, *The
//! tool's surface against the touched object's surface*).
//!
//! `cargo bench -p collette_ist --bench shell_press`

use collette::shape::box_buffers;
use collette::{
    BuildOptions, ContactSet, Pose, QueryWorkspace, SignedDistanceGrid, SurfaceShell, TriMesh, overlap_field,
    overlap_shell, overlap_surfaces,
};
use criterion::Criterion;
use glam::{Quat, Vec3};
use std::hint::black_box;

fn main() {
    let half = Vec3::new(0.1, 0.02, 0.1);
    let (v, t) = box_buffers(half);
    let slab = TriMesh::new(v, t).expect("slab");
    let grid = SignedDistanceGrid::new(&slab, 128).expect("grid");
    let (slab_tree, _) = collette::build(&slab, &BuildOptions::spheres(1000), &mut |_| {}).expect("slab tree");
    let slab_pose = Pose::from_translation(Vec3::new(0.0, -half.y, 0.0));
    let gem = collette::scene::brilliant_cut(0.01);
    let (gem_tree, _) = collette::build(&gem, &BuildOptions::spheres(1000), &mut |_| {}).expect("gem tree");
    let shell = SurfaceShell::new(&gem, 0.0005).expect("shell");
    let gem_grid = SignedDistanceGrid::new(&gem, 64).expect("gem grid");
    let slab_shell = SurfaceShell::new(&slab, 0.001).expect("slab shell");
    // The gem's culet (its point) down, turned a little: its lowest point at y = 0 before the press.
    let turn = Quat::from_rotation_x(3.0);
    let lowest = gem.vertices().iter().map(|v| (turn * *v).y).fold(f32::MAX, f32::min);
    let mut c = Criterion::default().configure_from_args();
    let mut group = c.benchmark_group("shell_press");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    for depth_mm in [0.1f32, 1.0, 5.0] {
        let pose = Pose::new(Vec3::new(0.003, -lowest - depth_mm * 1e-3, -0.002), turn);
        let field = overlap_field(&gem_tree, &pose, &slab_tree, &grid, &slab_pose, &mut ws, &mut set);
        let surface = overlap_shell(&shell, &pose, &grid, &slab_pose, &mut ws, &mut set);
        let both = overlap_surfaces(&shell, &gem_grid, &pose, &slab_shell, &grid, &slab_pose, &mut ws, &mut set);
        eprintln!(
            "shell_press/{depth_mm} mm: spheres {:.3e} m³ ({} nodes), surface {:.3e} m³ ({} of {} triangles inside), \
             both surfaces {:.3e} m³ ({} nodes)",
            field.total_volume,
            field.node_pairs,
            surface.total_volume,
            surface.leaf_pairs,
            shell.triangles().len(),
            both.total_volume,
            both.node_pairs
        );
        group.bench_function(format!("spheres_against_grid/{depth_mm}mm"), |b| {
            b.iter(|| overlap_field(&gem_tree, black_box(&pose), &slab_tree, &grid, &slab_pose, &mut ws, &mut set))
        });
        group.bench_function(format!("surface_against_grid/{depth_mm}mm"), |b| {
            b.iter(|| overlap_shell(&shell, black_box(&pose), &grid, &slab_pose, &mut ws, &mut set))
        });
        group.bench_function(format!("both_surfaces/{depth_mm}mm"), |b| {
            b.iter(|| {
                overlap_surfaces(&shell, &gem_grid, black_box(&pose), &slab_shell, &grid, &slab_pose, &mut ws, &mut set)
            })
        });
    }
    group.finish();
    c.final_summary();
}
