//! The tool's surface against an object's distance grid (`overlap_shell`): exact on flat faces.

use collette::shape::{box_buffers, uv_sphere_buffers};
use collette::{ContactSet, Pose, QueryWorkspace, SignedDistanceGrid, SurfaceShell, TriMesh};
use glam::{Quat, Vec3};
use std::f32::consts::PI;

fn mesh((v, t): (Vec<Vec3>, Vec<[u32; 3]>)) -> TriMesh {
    TriMesh::new(v, t).expect("mesh")
}

/// The force (Σ volume × normal) and the moment of the push (Σ point × volume × normal) of `set`.
fn push(set: &ContactSet) -> (Vec3, Vec3) {
    set.as_slice()
        .iter()
        .fold((Vec3::ZERO, Vec3::ZERO), |(f, m), c| (f + c.normal * c.volume, m + c.point.cross(c.normal * c.volume)))
}

/// A 10 cm slab, its top face at y = 0, and its grid.
fn slab() -> (SignedDistanceGrid, Pose) {
    let half = Vec3::new(0.05, 0.01, 0.05);
    let grid = SignedDistanceGrid::new(&mesh(box_buffers(half)), 64).expect("grid");
    (grid, Pose::from_translation(Vec3::new(0.0, -half.y, 0.0)))
}

/// A mesh's shell (edges of at most `edge`) and grid (`voxels` along its longest side).
struct Surfaced {
    shell: SurfaceShell,
    grid: SignedDistanceGrid,
}

fn surfaced(mesh: &TriMesh, edge: f32, voxels: usize) -> Surfaced {
    Surfaced {
        shell: SurfaceShell::new(mesh, edge).expect("shell"),
        grid: SignedDistanceGrid::new(mesh, voxels).expect("grid"),
    }
}

/// Both surfaces of `a` at `at` against `b` at `b_at`, within `budget`.
fn both(
    (a, at): (&Surfaced, &Pose),
    (b, b_at): (&Surfaced, &Pose),
    budget: collette::Budget,
    ws: &mut QueryWorkspace,
    set: &mut ContactSet,
) -> collette::OverlapResult {
    collette::overlap_surfaces_budgeted(&a.shell, &a.grid, at, &b.shell, &b.grid, b_at, budget, ws, set)
}

#[test]
fn a_cube_corner_pressed_into_a_face_measures_the_exact_tetrahedron() {
    let (grid, slab_pose) = slab();
    let h = 0.01;
    let shell = SurfaceShell::new(&mesh(box_buffers(Vec3::splat(h))), 0.001).expect("shell");
    let down = Quat::from_rotation_arc(Vec3::splat(-1.0).normalize(), -Vec3::Y);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    for (depth, spin) in [(1e-4, 0.3), (5e-4, 1.0), (2e-3, 2.0), (6e-3, 4.0)] {
        let corner = Vec3::new(0.004, -depth, -0.007);
        let pose = Pose::new(corner + Vec3::Y * (h * 3f32.sqrt()), Quat::from_rotation_y(spin) * down);
        let result = collette::overlap_shell(&shell, &pose, &grid, &slab_pose, &mut ws, &mut set);
        let exact = 3f32.sqrt() / 2.0 * depth.powi(3);
        let centroid = corner + Vec3::Y * (0.75 * depth);
        assert!((result.total_volume / exact - 1.0).abs() < 1e-3, "{depth}: {} against {exact}", result.total_volume);
        let (force, moment) = push(&set);
        assert!((force.length() / exact - 1.0).abs() < 1e-3, "{depth}: push {force}");
        assert!(force.normalize().angle_between(Vec3::Y).to_degrees() < 0.05, "{depth}: push {force}");
        // The push acts through the overlap's centroid: its moment is centroid × force.
        let off = (moment - centroid.cross(force)).length() / force.length();
        assert!(off < 1e-5, "{depth}: the push acts {off} m off the centroid");
    }
}

#[test]
fn a_cylinder_lying_on_a_face_pushes_through_its_segment() {
    let (grid, slab_pose) = slab();
    let (r, half_len, sides) = (0.015f32, 0.03f32, 96u32);
    let mut v = vec![Vec3::new(0.0, 0.0, -half_len), Vec3::new(0.0, 0.0, half_len)];
    for i in 0..sides {
        let a = i as f32 / sides as f32 * 2.0 * PI;
        v.push(Vec3::new(r * a.cos(), r * a.sin(), -half_len));
        v.push(Vec3::new(r * a.cos(), r * a.sin(), half_len));
    }
    let mut t = Vec::new();
    for i in 0..sides {
        let (b0, t0) = (2 + 2 * i, 3 + 2 * i);
        let (b1, t1) = (2 + 2 * ((i + 1) % sides), 3 + 2 * ((i + 1) % sides));
        t.extend([[0, b1, b0], [1, t0, t1], [b0, b1, t1], [b0, t1, t0]]);
    }
    let shell = SurfaceShell::new(&mesh((v, t)), 0.0005).expect("shell");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let depth = 0.002;
    let c = Vec3::new(0.003, r - depth, 0.002);
    let pose = Pose::new(c, Quat::from_rotation_y(0.7));
    let result = collette::overlap_shell(&shell, &pose, &grid, &slab_pose, &mut ws, &mut set);
    let (force, moment) = push(&set);
    // The push acts on the vertical line through the axis's middle.
    let arm = force.cross(moment) / force.length_squared();
    assert!(!set.truncated && set.len() < 200, "{} contacts", set.len());
    assert!(result.total_volume > 0.0 && (force.length() / result.total_volume - 1.0).abs() < 1e-3);
    assert!(Vec3::new(arm.x - c.x, 0.0, arm.z - c.z).length() < 1e-4, "arm {arm}");
}

#[test]
fn a_finely_split_sphere_pressed_into_a_face_measures_its_cap() {
    let (grid, slab_pose) = slab();
    let r = 0.01;
    let shell = SurfaceShell::new(&mesh(uv_sphere_buffers(r, 96, 192)), 0.0005).expect("shell");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    for depth in [2e-4, 1e-3, 4e-3] {
        let c = Vec3::new(-0.002, r - depth, 0.005);
        let result = collette::overlap_shell(
            &shell,
            &Pose::new(c, Quat::from_rotation_x(0.4)),
            &grid,
            &slab_pose,
            &mut ws,
            &mut set,
        );
        // The polygon's cap lies a little inside the sphere's (its facets sag by up to 3 µm).
        let cap = PI * depth * depth * (3.0 * r - depth) / 3.0;
        assert!((result.total_volume / cap - 1.0).abs() < 0.03, "{depth}: {} against {cap}", result.total_volume);
        let (force, moment) = push(&set);
        assert!(force.normalize().angle_between(Vec3::Y).to_degrees() < 0.05, "{depth}: {force}");
        // A sphere's push passes through its centre's vertical.
        let arm = force.cross(moment) / force.length_squared();
        assert!(Vec3::new(arm.x - c.x, 0.0, arm.z - c.z).length() < 1e-5, "{depth}: arm {arm}");
    }
}

#[test]
fn a_shell_outside_the_object_measures_nothing_and_a_budget_stops_it() {
    let (grid, slab_pose) = slab();
    let shell = SurfaceShell::new(&mesh(box_buffers(Vec3::splat(0.01))), 0.001).expect("shell");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let above = Pose::from_translation(Vec3::new(0.0, 0.015, 0.0));
    let result = collette::overlap_shell(&shell, &above, &grid, &slab_pose, &mut ws, &mut set);
    assert_eq!((result.total_volume, set.len(), result.leaf_pairs), (0.0, 0, 0));
    assert!(
        result.node_pairs < 250,
        "culled well above the leaves (of about 1,200 nodes): {} nodes",
        result.node_pairs
    );
    let into = Pose::from_translation(Vec3::new(0.0, 0.008, 0.0));
    let whole = collette::overlap_shell(&shell, &into, &grid, &slab_pose, &mut ws, &mut set);
    assert!(whole.complete && (whole.total_volume / (0.02 * 0.02 * 0.002) - 1.0).abs() < 1e-3, "{whole:?}");
    let cut = collette::overlap_shell_budgeted(
        &shell,
        &into,
        &grid,
        &slab_pose,
        collette::Budget::NodePairs(20),
        &mut ws,
        &mut set,
    );
    assert!(!cut.complete && set.truncated && cut.node_pairs == 20, "{cut:?}");
}

#[test]
fn two_surfaces_measure_a_corner_and_a_sphere_through_a_thin_plate_exactly() {
    // A cube's corner into a slab: the tetrahedron, through its centroid, straight up.
    let slab_pose = Pose::from_translation(Vec3::new(0.0, -0.01, 0.0));
    let slab = surfaced(&mesh(box_buffers(Vec3::new(0.05, 0.01, 0.05))), 0.0005, 64);
    let h = 0.01;
    let cube = surfaced(&mesh(box_buffers(Vec3::splat(h))), 0.001, 128);
    let down = Quat::from_rotation_arc(Vec3::splat(-1.0).normalize(), -Vec3::Y);
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    // 0.1 mm: thinner than the cube's grid can draw (the columns'); 3 mm: the boundary's.
    for depth in [1e-4, 3e-3] {
        let corner = Vec3::new(0.004, -depth, -0.007);
        let pose = Pose::new(corner + Vec3::Y * (h * 3f32.sqrt()), Quat::from_rotation_y(0.5) * down);
        let result = both((&cube, &pose), (&slab, &slab_pose), collette::Budget::Unlimited, &mut ws, &mut set);
        let exact = 3f32.sqrt() / 2.0 * depth.powi(3);
        assert!((result.total_volume / exact - 1.0).abs() < 0.01, "{depth}: {} against {exact}", result.total_volume);
        let c = set.as_slice()[0];
        assert!(set.len() == 1 && c.normal.angle_between(Vec3::Y).to_degrees() < 0.5, "{depth}: {c:?}");
        assert!(c.point.distance(corner + Vec3::Y * (0.75 * depth)) < 0.02 * depth.max(2.5e-3), "{depth}: {c:?}");
    }

    // A 1 cm ball pushed 6 mm through a 4 mm plate: its part inside the plate is a slice between two
    // planes, which the ball's columns (to the nearer face) get wrong, and the boundary does not.
    let plate = surfaced(&mesh(box_buffers(Vec3::new(0.03, 0.002, 0.03))), 0.001, 128);
    let r = 0.005;
    let ball = surfaced(&mesh(uv_sphere_buffers(r, 96, 192)), 0.0005, 64);
    // The ball's centre 1 mm above the plate's middle: its bottom 4 mm under the top face, 2 mm past the
    // bottom face.
    let centre = Vec3::new(0.0, 0.001, 0.0);
    let cap = |h: f32| PI * h * h * (3.0 * r - h) / 3.0;
    // The slice from 3 mm under the centre to 1 mm over it: the cap under the top face less the cap under the bottom face.
    let slice = cap(r + 0.001) - cap(r - 0.003);
    let at = Pose::from_translation(centre);
    let result = both((&ball, &at), (&plate, &Pose::IDENTITY), collette::Budget::Unlimited, &mut ws, &mut set);
    assert!((result.total_volume / slice - 1.0).abs() < 0.01, "{} against {slice}", result.total_volume);
    let columns = collette::overlap_shell(&ball.shell, &at, &plate.grid, &Pose::IDENTITY, &mut ws, &mut set);
    assert!((columns.total_volume / slice - 1.0).abs() > 0.05, "the columns miss it: {}", columns.total_volume);
}

#[test]
fn a_ball_pressed_past_a_thin_plates_middle_is_pushed_back_the_way_it_came() {
    // Past the middle of a 4 mm plate a column from the ball's surface runs to the plate's far face and
    // points through it; the push follows the way out (−∫ n dA over the ball's surface inside) instead.
    let plate = mesh(box_buffers(Vec3::new(0.03, 0.002, 0.03)));
    let grid = SignedDistanceGrid::new(&plate, 128).expect("grid");
    let r = 0.005;
    let shell = SurfaceShell::new(&mesh(uv_sphere_buffers(r, 96, 192)), 0.0005).expect("shell");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    // The ball's bottom 3 mm and 3.5 mm under the top face (inside the plate), and 4 mm (through it).
    for (bottom, way) in [(-0.001, Vec3::Y), (-0.0015, Vec3::Y), (-0.002, Vec3::Y)] {
        let at = Pose::new(Vec3::new(0.001, bottom + r, -0.002), Quat::from_rotation_z(0.3));
        let result = collette::overlap_shell(&shell, &at, &grid, &Pose::IDENTITY, &mut ws, &mut set);
        let (force, _) = push(&set);
        let volume = result.total_volume;
        assert!(volume > 0.0 && (force.length() / volume - 1.0).abs() < 1e-3, "{bottom}: {volume}, {force}");
        let off = force.normalize().angle_between(way).to_degrees();
        assert!(off < 0.5, "bottom at {bottom}: pushed {off}° off {way}");
    }
}

#[test]
fn a_ball_pressed_beside_a_blocks_edge_is_pushed_the_way_out() {
    // A block filling x < 0, y < 0 near its edge; a 5 mm ball 3 mm into its top face, its centre 2 mm
    // from the side face. The way that shrinks the overlap fastest, −∫ n dA over the ball's surface
    // inside, is (by the divergence theorem) the area of the overlap's flat face on the top plane along
    // +y plus that of its face on the side plane along +x: two discs less a segment, and a segment. Near
    // the edge the columns run to the side face and push towards −x; the push follows the way out.
    let block = mesh(box_buffers(Vec3::splat(0.02)));
    let grid = SignedDistanceGrid::new(&block, 128).expect("grid");
    let block_pose = Pose::from_translation(Vec3::new(-0.02, -0.02, 0.0));
    let r = 0.005f32;
    let shell = SurfaceShell::new(&mesh(uv_sphere_buffers(r, 192, 384)), 0.0005).expect("shell");
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let (depth, off) = (0.003f32, 0.002f32);
    let at = Pose::new(Vec3::new(-off, r - depth, 0.001), Quat::from_rotation_z(0.3));
    collette::overlap_shell(&shell, &at, &grid, &block_pose, &mut ws, &mut set);
    let (force, _) = push(&set);
    let segment = |radius: f32, h: f32| radius * radius * (h / radius).acos() - h * (radius * radius - h * h).sqrt();
    let a = (r * r - (r - depth).powi(2)).sqrt();
    let b = (r * r - off * off).sqrt();
    let way = Vec3::new(segment(b, r - depth), PI * a * a - segment(a, off), 0.0).normalize();
    let off_way = force.normalize().angle_between(way).to_degrees();
    assert!(off_way < 1.0, "pushed {off_way}° off the way out {way}: {force}");
}

#[test]
fn two_surfaces_cut_short_by_their_budget_answer_with_the_columns() {
    let plate = surfaced(&mesh(box_buffers(Vec3::new(0.03, 0.002, 0.03))), 0.001, 128);
    let ball = surfaced(&mesh(uv_sphere_buffers(0.005, 48, 96)), 0.0005, 64);
    let at = Pose::from_translation(Vec3::new(0.0, 0.004, 0.0));
    let (mut ws, mut set) = (QueryWorkspace::new(), ContactSet::new());
    let columns = collette::overlap_shell(&ball.shell, &at, &plate.grid, &Pose::IDENTITY, &mut ws, &mut set);
    let column_contacts = set.as_slice().to_vec();
    let whole = both((&ball, &at), (&plate, &Pose::IDENTITY), collette::Budget::Unlimited, &mut ws, &mut set);
    assert!(whole.complete && set.len() == 1 && whole.node_pairs > columns.node_pairs + 10, "{whole:?}");
    let mut run = |pairs| {
        let budget = collette::Budget::NodePairs(pairs);
        let result = both((&ball, &at), (&plate, &Pose::IDENTITY), budget, &mut ws, &mut set);
        (result, set.as_slice().to_vec())
    };
    // Cut short in the boundary: the columns' contacts, whole.
    let (cut, contacts) = run(columns.node_pairs + 10);
    assert!(!cut.complete && cut.total_volume == columns.total_volume && contacts == column_contacts, "{cut:?}");
    // Cut short in the columns: part of them.
    let (cut, contacts) = run(columns.node_pairs / 2);
    assert!(!cut.complete && contacts.len() < column_contacts.len(), "{cut:?}");
    // Budget enough: the whole answer.
    let (enough, _) = run(whole.node_pairs);
    assert!(enough.complete && enough.total_volume == whole.total_volume, "{enough:?}");
}
