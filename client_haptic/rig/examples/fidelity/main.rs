//! fidelity: how close the rendered force and torque come to exact answers, on scenes whose answer is
//! known (the approach of Weller et al.'s benchmarking suite for 6-DOF collision response, VRST 2010).
//!
//! `cargo run --release -p haptic_rig --example fidelity -- --json`
//!
//! Volumetric rendering (Eq. 1 and 2 with ε_c = 1, no damping or friction: the force is the overlap
//! volume along the contact normals) is judged against the penalty the exact overlap gives: the exact
//! volume along the exact normal, its torque about a handle point off the tool from the exact overlap's
//! centroid. Two trees (the tool's against the object's), the tree against the object's surface grid,
//! the tool's surface (its shell) against the grid, and both surfaces each against the other's grid.
//! The 3-DOF proxy is judged by where it holds the tip: its contact point against the exact closest
//! point of the surface, held on the object's packing or on its surface grid. Scenes: a sphere, a box's edge, a box's corner and a cylinder on its side
//! pressed into a slab, a sphere into a sphere; the proxy's tip into the slab, the sphere and the box
//! (faces, edges and corners), at depths from 0.1 to 5 mm (one pose in ten 5–10 mm), random places and
//! turns about the normal. Mesh pairs (a 1 cm gem on the bunny and on a torus, a ring on the bunny) at
//! random surface points and turns, 1–10 mm deep, against a Monte Carlo reference ([`meshes`]).

mod meshes;

use std::f32::consts::PI;
use std::sync::Arc;

use clap::Parser;
use collette::shape::{box_buffers, uv_sphere_buffers};
use collette::{BuildOptions, ContactSet, InnerSphereTree, QueryWorkspace, SignedDistanceGrid, SurfaceShell, TriMesh};
use forcecomp::{Ball, BodyMotion, GodObject, Material, ProxyConfig};
use glam::{Quat, Vec3};
use haptic_common::Pose;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[derive(Parser, Debug)]
#[command(about = "Judges rendered forces and torques against exact answers on scenes whose answer is known.")]
struct Args {
    /// Poses per scene.
    #[arg(long, default_value_t = 2000)]
    poses: usize,
    /// Spheres in every tree.
    #[arg(long, default_value_t = 5000)]
    spheres: usize,
    /// Voxels along the longest side of the objects' surface grids.
    #[arg(long, default_value_t = 128)]
    grid: usize,
    /// Poses per mesh scene (each with a Monte Carlo reference of `--samples` points).
    #[arg(long, default_value_t = 200)]
    mesh_poses: usize,
    /// Monte Carlo points per mesh pose, in the box the overlap can occupy.
    #[arg(long, default_value_t = 1_000_000)]
    samples: usize,
    /// Longest edge of the shapes' surface shells, mm.
    #[arg(long, default_value_t = 0.5)]
    shell_edge_mm: f32,
    /// Seed of the poses.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// End with one JSON line per rendering.
    #[arg(long)]
    json: bool,
}

/// Errors end the program on one line.
fn main() -> std::process::ExitCode {
    match run(Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// A shape's tree, surface grid and surface shell.
struct Shape {
    tree: Arc<InnerSphereTree>,
    grid: SignedDistanceGrid,
    shell: SurfaceShell,
}

fn shape(buffers: (Vec<Vec3>, Vec<[u32; 3]>), args: &Args) -> anyhow::Result<Shape> {
    shape_of(&TriMesh::new(buffers.0, buffers.1)?, args)
}

fn shape_of(mesh: &TriMesh, args: &Args) -> anyhow::Result<Shape> {
    let (tree, _) = collette::build(mesh, &BuildOptions::spheres(args.spheres), &mut |_| {})?;
    let grid = SignedDistanceGrid::new(mesh, args.grid)?;
    // Every shape has its shell: the tool's for the surface rendering, both for the two surfaces.
    let shell = SurfaceShell::new(mesh, args.shell_edge_mm * 1e-3)?;
    Ok(Shape { tree: Arc::new(tree), grid, shell })
}

/// A closed cylinder along z: radius `r`, half length `h`, `n` sides.
fn cylinder_buffers(r: f32, h: f32, n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = vec![Vec3::new(0.0, 0.0, -h), Vec3::new(0.0, 0.0, h)];
    for i in 0..n {
        let a = i as f32 / n as f32 * 2.0 * PI;
        v.push(Vec3::new(r * a.cos(), r * a.sin(), -h));
        v.push(Vec3::new(r * a.cos(), r * a.sin(), h));
    }
    let mut t = Vec::new();
    for i in 0..n {
        let (b0, t0) = (2 + 2 * i, 3 + 2 * i);
        let (b1, t1) = (2 + 2 * ((i + 1) % n), 3 + 2 * ((i + 1) % n));
        t.push([0, b1, b0]);
        t.push([1, t0, t1]);
        t.push([b0, b1, t1]);
        t.push([b0, t1, t0]);
    }
    (v, t)
}

/// Sizes of the scenes, m.
const SPHERE_R: f32 = 0.02;
const BALL_R: f32 = 0.03;
const CUBE_HALF: f32 = 0.015;
const CYL_R: f32 = 0.015;
const CYL_HALF: f32 = 0.03;
const SLAB_HALF: Vec3 = Vec3::new(0.1, 0.02, 0.1);
/// The point torques are taken about: a handle off the tool's centre.
const HANDLE: Vec3 = Vec3::new(0.04, 0.05, 0.03);

/// The penalty the exact overlap gives: its volume along the normal, and the overlap's centroid.
#[derive(Clone, Copy, Debug)]
struct Exact {
    volume: f32,
    normal: Vec3,
    centroid: Vec3,
}

/// Volume of a spherical cap of height `h` on a sphere of radius `r`.
fn cap_volume(r: f32, h: f32) -> f32 {
    PI * h * h * (3.0 * r - h) / 3.0
}

/// Distance from a sphere's centre to the centroid of its cap of height `h`.
fn cap_centroid(r: f32, h: f32) -> f32 {
    3.0 * (2.0 * r - h).powi(2) / (4.0 * (3.0 * r - h))
}

/// A sphere of radius `r` centred at `c` pressed `d` into the plane y = 0 from above.
fn sphere_on_plane(r: f32, c: Vec3, d: f32) -> Exact {
    Exact { volume: cap_volume(r, d), normal: Vec3::Y, centroid: c - Vec3::Y * cap_centroid(r, d) }
}

/// Sphere `r1` at `c1` overlapping sphere `r2` at `c2` (the tool is sphere 1).
fn sphere_on_sphere(r1: f32, c1: Vec3, r2: f32, c2: Vec3) -> Exact {
    let dist = c1.distance(c2);
    let u = (c1 - c2) / dist;
    // The radical plane lies `a2` from c2 along u; the lens is a cap of each sphere on either side.
    let a2 = (dist * dist + r2 * r2 - r1 * r1) / (2.0 * dist);
    let (h2, h1) = (r2 - a2, r1 - (dist - a2));
    let (v1, v2) = (cap_volume(r1, h1), cap_volume(r2, h2));
    let (g1, g2) = (c1 - u * cap_centroid(r1, h1), c2 + u * cap_centroid(r2, h2));
    Exact { volume: v1 + v2, normal: u, centroid: (g1 * v1 + g2 * v2) / (v1 + v2) }
}

/// A box edge of length `len` lying level along the plane, its faces at 45°, `d` deep: a prism of
/// cross-section d² whose centroid is d/3 below the plane, under the edge's middle `m`.
fn edge_on_plane(len: f32, m: Vec3, d: f32) -> Exact {
    Exact { volume: len * d * d, normal: Vec3::Y, centroid: Vec3::new(m.x, -d / 3.0, m.z) }
}

/// A cube corner at `corner`, its body diagonal vertical, `d` deep: a tetrahedron of legs √3·d,
/// volume (√3/2)·d³, centroid a quarter of the way up.
fn corner_on_plane(corner: Vec3, d: f32) -> Exact {
    Exact { volume: 3f32.sqrt() / 2.0 * d.powi(3), normal: Vec3::Y, centroid: corner + Vec3::Y * (0.75 * d) }
}

/// A cylinder of radius `r`, length `len`, lying on its side with its axis at `c`, `d` deep: a
/// circular segment times the length.
fn cylinder_on_plane(r: f32, len: f32, c: Vec3, d: f32) -> Exact {
    let theta = 2.0 * ((r - d) / r).acos();
    let area = 0.5 * r * r * (theta - theta.sin());
    let below = 4.0 * r * (theta / 2.0).sin().powi(3) / (3.0 * (theta - theta.sin()));
    Exact { volume: area * len, normal: Vec3::Y, centroid: c - Vec3::Y * below }
}

/// The poses' random numbers (seeded).
struct Dice(ChaCha8Rng);

impl Dice {
    /// Uniform in 0..1.
    fn roll(&mut self) -> f32 {
        self.0.random()
    }

    /// A depth: log-uniform over 0.1–5 mm, one in ten 5–10 mm.
    fn depth(&mut self) -> f32 {
        if self.roll() < 0.1 { 0.005 + 0.005 * self.roll() } else { 1e-4 * 50f32.powf(self.roll()) }
    }

    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.roll(), self.roll(), self.roll()) * 2.0 - Vec3::ONE;
            if (0.01..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}

/// Angle between two vectors, degrees.
fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    a.normalize_or_zero().dot(b.normalize_or_zero()).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Errors of one rendering over many poses.
#[derive(Default)]
struct Errors {
    /// The depth of each volumetric pose, m.
    depth: Vec<f32>,
    direction_deg: Vec<f32>,
    magnitude_pct: Vec<f32>,
    torque_deg: Vec<f32>,
    contact_mm: Vec<f32>,
    /// How long each volumetric query took, µs.
    query_us: Vec<f32>,
}

impl Errors {
    /// The volumetric errors of the poses whose depth lies in `low..high` (m).
    fn band(&self, low: f32, high: f32) -> Errors {
        let pick = |v: &[f32]| -> Vec<f32> {
            v.iter().zip(&self.depth).filter(|(_, d)| (low..high).contains(*d)).map(|(x, _)| *x).collect()
        };
        Errors {
            depth: pick(&self.depth),
            direction_deg: pick(&self.direction_deg),
            magnitude_pct: pick(&self.magnitude_pct),
            torque_deg: pick(&self.torque_deg),
            contact_mm: Vec::new(),
            query_us: pick(&self.query_us),
        }
    }

    fn add(&mut self, other: Errors) {
        self.depth.extend(other.depth);
        self.direction_deg.extend(other.direction_deg);
        self.magnitude_pct.extend(other.magnitude_pct);
        self.torque_deg.extend(other.torque_deg);
        self.contact_mm.extend(other.contact_mm);
        self.query_us.extend(other.query_us);
    }
}

/// The `q` quantile (0–1) of `values` (NaN when empty).
fn quantile(values: &[f32], q: f32) -> f32 {
    if values.is_empty() {
        return f32::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * q).round() as usize]
}

/// The tool's force and torque about the handle through `overlap` (ε_c = 1), against `exact`.
fn judge(set: &ContactSet, tool: &Pose, exact: &Exact, depth: f32, errors: &mut Errors) {
    let handle = tool.translation + HANDLE;
    let unit = Material { stiffness_n_per_m3: 1.0, damping_ns_per_m: 0.0, friction: 0.0, texture: None };
    let rendered =
        forcecomp::volumetric_penalty(set, &BodyMotion::at_rest(handle), &BodyMotion::at_rest(Vec3::ZERO), &unit);
    let force = exact.normal * exact.volume;
    let torque = (exact.centroid - handle).cross(force);
    errors.depth.push(depth);
    errors.direction_deg.push(angle_deg(rendered.force, force));
    errors.magnitude_pct.push((rendered.force.length() / force.length() - 1.0).abs() * 100.0);
    errors.torque_deg.push(angle_deg(rendered.torque, torque));
}

/// The volumetric renderings of one scene: `place` gives, for a depth and the dice, the tool's pose and
/// the exact answer.
fn volumetric(
    tool: &Shape,
    object: &Shape,
    object_pose: &Pose,
    poses: usize,
    dice: &mut Dice,
    place: impl Fn(f32, &mut Dice) -> (Pose, Exact),
) -> [Errors; 4] {
    let mut errors: [Errors; 4] = Default::default();
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    for _ in 0..poses {
        let depth = dice.depth();
        let (pose, exact) = place(depth, dice);
        measure_all(tool, object, &pose, object_pose, &mut ws, &mut set, |set, i, us| {
            judge(set, &pose, &exact, depth, &mut errors[i]);
            errors[i].query_us.push(us);
        });
    }
    errors
}

/// The volumetric renderings, in the order of [`VOLUMETRIC`]: each measured into `set`, then handed to
/// `judge` with its index and how long the query took (µs).
fn measure_all(
    tool: &Shape,
    object: &Shape,
    pose: &Pose,
    object_pose: &Pose,
    ws: &mut QueryWorkspace,
    set: &mut ContactSet,
    mut judge: impl FnMut(&ContactSet, usize, f32),
) {
    let us = |started: std::time::Instant| started.elapsed().as_secs_f32() * 1e6;
    let started = std::time::Instant::now();
    collette::overlap(&tool.tree, pose, &object.tree, object_pose, ws, set);
    judge(set, 0, us(started));
    let started = std::time::Instant::now();
    collette::overlap_field(&tool.tree, pose, &object.tree, &object.grid, object_pose, ws, set);
    judge(set, 1, us(started));
    let started = std::time::Instant::now();
    collette::overlap_shell(&tool.shell, pose, &object.grid, object_pose, ws, set);
    judge(set, 2, us(started));
    let started = std::time::Instant::now();
    collette::overlap_surfaces(&tool.shell, &tool.grid, pose, &object.shell, &object.grid, object_pose, ws, set);
    judge(set, 3, us(started));
}

/// The volumetric renderings: the table's name, the summary's name and the JSON's.
const VOLUMETRIC: [(&str, &str, &str); 4] = [
    ("volumetric, two trees", "two trees", "volumetric_trees"),
    ("volumetric, tree against grid", "tree against grid", "volumetric_grid"),
    ("volumetric, surface against grid", "surface against grid", "volumetric_surface"),
    ("volumetric, two surfaces", "two surfaces", "volumetric_surfaces"),
];

/// The 3-DOF proxy's tip (radius 4 mm, as the rig's default) pressed from `outside` to `inside`, held
/// on the object's packing or (`on_grid`) its surface grid; its contact point (the proxy less its
/// hold-off along the normal) against `surface`, the exact closest point of the object's surface to
/// `inside`.
#[allow(clippy::too_many_arguments)]
fn proxy(
    object: &Shape,
    object_pose: &Pose,
    on_grid: bool,
    outside: Vec3,
    inside: Vec3,
    surface: Vec3,
    errors: &mut Errors,
) {
    let config = ProxyConfig { friction: 0.0, tip_radius: 0.004, ..ProxyConfig::default() };
    let mut balls = Vec::new();
    if !on_grid {
        let mut ws = QueryWorkspace::new();
        collette::query::spheres_near(&object.tree, object_pose, inside, 0.03, &mut ws, |center, radius| {
            balls.push(Ball { center, radius })
        });
    }
    let field = haptic_rig::force::GridAt { grid: &object.grid, pose: *object_pose };
    let mut god = GodObject::new();
    let mut press = |at: Vec3| match on_grid {
        true => god.update_with(&config, at, Vec3::ZERO, &balls, &field, 1.0),
        false => god.update(&config, at, Vec3::ZERO, &balls, 1.0),
    };
    press(outside);
    for _ in 0..20 {
        press(inside);
    }
    if !god.in_contact() {
        errors.contact_mm.push(f32::INFINITY);
        return;
    }
    // The proxy rests where the tip overlaps the surface by a cap of SURFACE_CAP of its radius; its
    // normal points out of the object.
    let hold_off = config.tip_radius * (1.0 - forcecomp::proxy::SURFACE_CAP);
    let contact = god.proxy() - god.normal() * hold_off;
    errors.contact_mm.push(contact.distance(surface) * 1000.0);
}

fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.poses > 0, "--poses must be at least 1");
    anyhow::ensure!(args.samples >= 1000, "--samples must be at least 1000");
    let started = std::time::Instant::now();
    let sphere = shape(uv_sphere_buffers(SPHERE_R, 384, 768), &args)?;
    let ball = shape(uv_sphere_buffers(BALL_R, 384, 768), &args)?;
    let cube = shape(box_buffers(Vec3::splat(CUBE_HALF)), &args)?;
    let cylinder = shape(cylinder_buffers(CYL_R, CYL_HALF, 384), &args)?;
    let slab = shape(box_buffers(SLAB_HALF), &args)?;
    eprintln!("fidelity: trees and grids built in {:.1} s", started.elapsed().as_secs_f32());
    let slab_pose = Pose::from_translation(Vec3::new(0.0, -SLAB_HALF.y, 0.0));
    let mut dice = Dice(ChaCha8Rng::seed_from_u64(args.seed as u64));
    let spin = |dice: &mut Dice| Quat::from_rotation_y(dice.roll() * 2.0 * PI);
    let spot = |dice: &mut Dice| Vec3::new(dice.roll() - 0.5, 0.0, dice.roll() - 0.5) * 0.06;

    let mut table = Vec::new();
    let scenes: [(&str, &Shape, &Shape, Pose); 5] = [
        ("sphere on plane", &sphere, &slab, slab_pose),
        ("sphere on sphere", &sphere, &ball, Pose::IDENTITY),
        ("box edge on plane", &cube, &slab, slab_pose),
        ("box corner on plane", &cube, &slab, slab_pose),
        ("cylinder on its side", &cylinder, &slab, slab_pose),
    ];
    let mut all: [Errors; 4] = Default::default();
    for (i, (name, tool, object, object_pose)) in scenes.into_iter().enumerate() {
        let errors = volumetric(tool, object, &object_pose, args.poses, &mut dice, |d, dice| match i {
            0 => {
                let c = spot(dice) + Vec3::Y * (SPHERE_R - d);
                (Pose::new(c, spin(dice)), sphere_on_plane(SPHERE_R, c, d))
            }
            1 => {
                let u = dice.unit();
                let c = u * (SPHERE_R + BALL_R - d);
                (Pose::new(c, spin(dice)), sphere_on_sphere(SPHERE_R, c, BALL_R, Vec3::ZERO))
            }
            2 => {
                // Turned 45° about x, so that an edge along its local z lies lowest, then about y.
                let turn = spin(dice) * Quat::from_rotation_x(PI / 4.0);
                let m = spot(dice);
                let c = m + Vec3::Y * (CUBE_HALF * 2f32.sqrt() - d);
                (Pose::new(c, turn), edge_on_plane(2.0 * CUBE_HALF, m, d))
            }
            3 => {
                // The corner (-h, -h, -h) turned to point straight down.
                let down = Quat::from_rotation_arc(Vec3::splat(-1.0).normalize(), -Vec3::Y);
                let turn = spin(dice) * down;
                let corner = spot(dice) - Vec3::Y * d;
                let c = corner + Vec3::Y * (CUBE_HALF * 3f32.sqrt());
                (Pose::new(c, turn), corner_on_plane(corner, d))
            }
            _ => {
                let c = spot(dice) + Vec3::Y * (CYL_R - d);
                (Pose::new(c, spin(dice)), cylinder_on_plane(CYL_R, 2.0 * CYL_HALF, c, d))
            }
        });
        for ((rendering, _, _), (errors, all)) in VOLUMETRIC.iter().zip(errors.into_iter().zip(&mut all)) {
            table.push((name.to_string(), *rendering, quantiles(&errors)));
            all.add(errors);
        }
    }

    // Mesh pairs against the Monte Carlo reference: depths 1–10 mm (shallower overlaps of a pointed
    // tool are too few points for the reference; the primitives cover them).
    let mesh_started = std::time::Instant::now();
    let mut mesh_dice = Dice(ChaCha8Rng::seed_from_u64(args.seed as u64 + 2));
    let surface_samples = 1_000_000;
    let gem_mesh = collette::scene::brilliant_cut(0.01);
    let bunny_mesh = collette::scene::load_bunny(collette::scene::default_bunny_path())?;
    let closed = |(v, t): (Vec<Vec3>, Vec<[u32; 3]>)| TriMesh::new(v, t);
    let torus_mesh = closed(collette::shape::torus_buffers(0.03, 0.01, 96, 48))?;
    let ring_mesh = closed(collette::shape::torus_buffers(0.01, 0.004, 64, 32))?;
    let mut mesh_shape = |mesh: TriMesh, voxels: usize| -> anyhow::Result<meshes::MeshShape> {
        let shape = shape_of(&mesh, &args)?;
        Ok(meshes::MeshShape::new(mesh, shape, voxels, surface_samples, &mut mesh_dice))
    };
    let gem = mesh_shape(gem_mesh, 128)?;
    let ring = mesh_shape(ring_mesh, 128)?;
    let bunny = mesh_shape(bunny_mesh, 256)?;
    let torus = mesh_shape(torus_mesh, 256)?;
    eprintln!("fidelity: mesh scenes built in {:.1} s", mesh_started.elapsed().as_secs_f32());
    let mesh_scenes: [(&str, &meshes::MeshShape, &meshes::MeshShape); 3] =
        [("gem on bunny", &gem, &bunny), ("gem on torus", &gem, &torus), ("ring on bunny", &ring, &bunny)];
    let mut skipped = 0;
    for (name, tool, object) in mesh_scenes {
        let mut errors: [Errors; 4] = Default::default();
        let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
        let mut kept = 0;
        while kept < args.mesh_poses && kept + skipped < 20 * args.mesh_poses {
            let depth = if mesh_dice.roll() < 0.1 {
                0.005 + 0.005 * mesh_dice.roll()
            } else {
                1e-3 * 5f32.powf(mesh_dice.roll())
            };
            let turn = Quat::from_scaled_axis(mesh_dice.unit() * (mesh_dice.roll() * PI));
            let at = object.surface_point(&mut mesh_dice);
            let Some((pose, exact)) = meshes::press(tool, object, turn, at, depth, args.samples, &mut mesh_dice) else {
                skipped += 1;
                continue;
            };
            measure_all(&tool.shape, &object.shape, &pose, &Pose::IDENTITY, &mut ws, &mut set, |set, i, us| {
                judge(set, &pose, &exact, depth, &mut errors[i]);
                errors[i].query_us.push(us);
            });
            kept += 1;
        }
        for ((rendering, _, _), (errors, all)) in VOLUMETRIC.iter().zip(errors.into_iter().zip(&mut all)) {
            table.push((name.to_string(), *rendering, quantiles(&errors)));
            all.add(errors);
        }
    }
    eprintln!(
        "fidelity: mesh scenes judged in {:.1} s ({skipped} poses skipped: no overlap, one out of reach, or the \
         tool sunk whole)",
        mesh_started.elapsed().as_secs_f32()
    );

    // The proxy: the tip pressed into the slab, the ball and the cube, on their packings and on their
    // grids (the same poses for both).
    let (mut proxy_errors, mut proxy_grid_errors) = (Errors::default(), Errors::default());
    for (on_grid, rendering) in [(false, "3-DOF proxy on the packing"), (true, "3-DOF proxy on the grid")] {
        let mut dice = Dice(ChaCha8Rng::seed_from_u64(args.seed as u64 + 1));
        let mut slab_errors = Errors::default();
        for _ in 0..args.poses {
            let (d, at) = (dice.depth(), spot(&mut dice));
            proxy(&slab, &slab_pose, on_grid, at + Vec3::Y * 0.01, at - Vec3::Y * d, at, &mut slab_errors);
        }
        let mut ball_errors = Errors::default();
        for _ in 0..args.poses {
            let (d, u) = (dice.depth(), dice.unit());
            let (outside, inside) = (u * (BALL_R + 0.01), u * (BALL_R - d));
            proxy(&ball, &Pose::IDENTITY, on_grid, outside, inside, u * BALL_R, &mut ball_errors);
        }
        let mut cube_errors = Errors::default();
        let cube_pose = Pose::IDENTITY;
        for _ in 0..args.poses {
            // Straight in through a face, anywhere on it up to its edges (there the face is the nearest).
            let d = dice.depth().min(CUBE_HALF * 0.5);
            let (k, sign) = ((dice.roll() * 3.0) as usize % 3, if dice.roll() < 0.5 { -1.0 } else { 1.0 });
            let mut surface = (Vec3::new(dice.roll(), dice.roll(), dice.roll()) * 2.0 - Vec3::ONE) * (CUBE_HALF - d);
            surface[k] = sign * CUBE_HALF;
            let mut out = Vec3::ZERO;
            out[k] = sign;
            let (outside, inside) = (surface + out * 0.01, surface - out * d);
            proxy(&cube, &cube_pose, on_grid, outside, inside, surface, &mut cube_errors);
        }
        table.push(("tip into a plane".to_string(), rendering, quantiles(&slab_errors)));
        table.push(("tip into a sphere".to_string(), rendering, quantiles(&ball_errors)));
        table.push(("tip into a box".to_string(), rendering, quantiles(&cube_errors)));
        let all = if on_grid { &mut proxy_grid_errors } else { &mut proxy_errors };
        all.add(slab_errors);
        all.add(ball_errors);
        all.add(cube_errors);
    }

    println!(
        "| scene | rendering | direction p50 / p99 | magnitude p50 / p99 | torque direction p50 / p99 | contact p50 / p99 |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for (scene, rendering, q) in &table {
        println!("| {scene} | {rendering} | {} | {} | {} | {} |", q[0], q[1], q[2], q[3]);
    }
    println!();
    println!(
        "| rendering, all volumetric scenes | depth | direction p50 / p99 | magnitude p50 / p99 | torque direction p50 / p99 | query p50 / p99 |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for ((_, rendering, _), e) in VOLUMETRIC.iter().zip(&all) {
        for (band, low, high) in [("0.1–1 mm", 0.0, 0.001), ("1–5 mm", 0.001, 0.005), ("5–10 mm", 0.005, 1.0)] {
            let q = quantiles(&e.band(low, high));
            let time = quantiles_of(&e.band(low, high).query_us, "µs", 1);
            println!("| {rendering} | {band} | {} | {} | {} | {time} |", q[0], q[1], q[2]);
        }
    }
    println!(
        "fidelity: {} poses a primitive scene, {} a mesh scene ({} Monte Carlo points each), trees of {} spheres, \
         grids of {} voxels, in {:.1} s",
        args.poses,
        args.mesh_poses,
        args.samples,
        args.spheres,
        args.grid,
        started.elapsed().as_secs_f32()
    );
    if args.json {
        let volumetric = VOLUMETRIC.iter().zip(&all).map(|((_, _, json), e)| (*json, e));
        for (rendering, e) in volumetric.chain([("proxy", &proxy_errors), ("proxy_grid", &proxy_grid_errors)]) {
            let volumetric = rendering.starts_with("volumetric");
            let line = serde_json::json!({
                "rendering": rendering,
                "poses": e.direction_deg.len().max(e.contact_mm.len()),
                "direction_p99_deg": volumetric.then(|| quantile(&e.direction_deg, 0.99)),
                "magnitude_p99_pct": volumetric.then(|| quantile(&e.magnitude_pct, 0.99)),
                "torque_direction_p99_deg": volumetric.then(|| quantile(&e.torque_deg, 0.99)),
                "contact_p99_mm": (!volumetric).then(|| quantile(&e.contact_mm, 0.99)),
                "query_p50_us": volumetric.then(|| quantile(&e.query_us, 0.5)),
            });
            println!("{line}");
        }
    }
    Ok(())
}

/// One cell: p50 / p99 of `v` ("–" when empty).
fn quantiles_of(v: &[f32], unit: &str, digits: usize) -> String {
    if v.is_empty() {
        "–".to_string()
    } else {
        format!("{:.digits$} / {:.digits$} {unit}", quantile(v, 0.5), quantile(v, 0.99))
    }
}

/// The table's cells for one rendering of one scene: p50 / p99 of each error ("–" where it does not
/// apply).
fn quantiles(e: &Errors) -> [String; 4] {
    let cell = quantiles_of;
    [
        cell(&e.direction_deg, "°", 2),
        cell(&e.magnitude_pct, "%", 1),
        cell(&e.torque_deg, "°", 2),
        cell(&e.contact_mm, "mm", 3),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Volume and centroid of the part of a shape below y = 0 (or inside `inside`), by sampling a grid.
    fn sampled(low: Vec3, high: Vec3, n: usize, inside: impl Fn(Vec3) -> bool) -> (f32, Vec3) {
        let step = (high - low) / n as f32;
        let (mut count, mut sum) = (0usize, Vec3::ZERO);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let p = low + step * Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5);
                    if inside(p) {
                        count += 1;
                        sum += p;
                    }
                }
            }
        }
        (count as f32 * step.x * step.y * step.z, sum / count.max(1) as f32)
    }

    fn close(exact: Exact, (volume, centroid): (f32, Vec3), scale: f32) {
        assert!((exact.volume / volume - 1.0).abs() < 0.02, "volume {} sampled {volume}", exact.volume);
        assert!(exact.centroid.distance(centroid) < 0.01 * scale, "centroid {} sampled {centroid}", exact.centroid);
    }

    #[test]
    fn the_exact_answers_match_a_sampled_integration() {
        let d = 0.004;
        // Sphere on plane.
        let c = Vec3::new(0.01, SPHERE_R - d, 0.0);
        let s = sampled(c - Vec3::splat(SPHERE_R), c + Vec3::splat(SPHERE_R), 160, |p| {
            p.y < 0.0 && p.distance(c) < SPHERE_R
        });
        close(sphere_on_plane(SPHERE_R, c, d), s, SPHERE_R);
        // Sphere on sphere.
        let c1 = Vec3::new(0.3, 0.5, 0.2).normalize() * (SPHERE_R + BALL_R - d);
        let s =
            sampled(-Vec3::splat(0.06), Vec3::splat(0.06), 240, |p| p.distance(c1) < SPHERE_R && p.length() < BALL_R);
        close(sphere_on_sphere(SPHERE_R, c1, BALL_R, Vec3::ZERO), s, SPHERE_R);
        // Box edge (45°, along z) and corner.
        let turn = Quat::from_rotation_x(PI / 4.0);
        let m = Vec3::new(0.0, 0.0, 0.0);
        let c = m + Vec3::Y * (CUBE_HALF * 2f32.sqrt() - d);
        let in_cube = |pose: Pose| move |p: Vec3| pose.inverse().transform_point(p).abs().max_element() < CUBE_HALF;
        let edge_cube = in_cube(Pose::new(c, turn));
        let s =
            sampled(Vec3::new(-0.02, -0.005, -0.02), Vec3::new(0.02, 0.0, 0.02), 200, |p| p.y < 0.0 && edge_cube(p));
        close(edge_on_plane(2.0 * CUBE_HALF, m, d), s, CUBE_HALF);
        let down = Quat::from_rotation_arc(Vec3::splat(-1.0).normalize(), -Vec3::Y);
        let corner = -Vec3::Y * d;
        let corner_cube = in_cube(Pose::new(corner + Vec3::Y * (CUBE_HALF * 3f32.sqrt()), down));
        let s =
            sampled(Vec3::new(-0.01, -0.005, -0.01), Vec3::new(0.01, 0.0, 0.01), 200, |p| p.y < 0.0 && corner_cube(p));
        close(corner_on_plane(corner, d), s, 0.1 * CUBE_HALF);
        // Cylinder on its side (axis along z).
        let c = Vec3::Y * (CYL_R - d);
        let s = sampled(Vec3::new(-0.02, -0.005, -0.035), Vec3::new(0.02, 0.0, 0.035), 200, |p| {
            p.y < 0.0 && Vec3::new(p.x - c.x, p.y - c.y, 0.0).length() < CYL_R && p.z.abs() < CYL_HALF
        });
        close(cylinder_on_plane(CYL_R, 2.0 * CYL_HALF, c, d), s, CYL_R);
    }
}
