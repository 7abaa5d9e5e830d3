//! What a copy is to the hand: its Inner Sphere Tree (built, or loaded from the cache keyed by the
//! mesh's content hash), its surface grid, its briefed material as a force component, and the stylus's
//! gemstone and rendering for a device.
//!
//! You need this module to change how a copy feels. The running client hands what it builds here to
//! `bevy_haptics` ([`crate::bench`]); the lockstep rig the tests explore copies with takes the same
//! ([`crate::touch_bench`]). With volumetric rendering a copy also gets a signed distance grid of its
//! surface, so the gem's spheres are measured against the copy's real surface rather than its packing
//! (collette's `overlap_field`: the overlap within about 1 % of the true one, no packing bumps under a
//! smooth copy).

use std::path::PathBuf;
use std::sync::Arc;

use bevy::prelude::Resource;
use bevy_haptics::{ForceComponent, Ridges};
use collette::{BuildOptions, InnerSphereTree, SignedDistanceGrid, TriMesh};
use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::{ProxyRendering, Rendering, RigConfig, ToolSpec, WorkspaceMap};
use haptico::DeviceSpecs;
use heist_shared::artifact::{self, HapticMesh};
use heist_shared::protocol::ItemId;

use crate::device::DeviceChoice;
use crate::error::ClientError;

/// Diameter of the stylus's gemstone, m (a fine tip: the idol's notches are 16 mm wide).
pub const TOOL_DIAMETER_M: f32 = 0.006;
/// Depth at which a copy pushes back with its briefed stiffness (N/m) times the depth, m (see [`haptic_material`]).
pub const REFERENCE_DEPTH_M: f32 = 0.002;
/// The gem's sphere count.
const TOOL_SPHERES: usize = 200;
/// Id of the copy on the lockstep rig's collision thread.
pub(crate) const COPY_OBJECT: u32 = 1;

/// The stiffest material a copy can have, N/m (`artifact::MaterialClass`: hard 800, soft 300, within
/// 200–1000): a 3-DOF device that cannot render it gets every copy's stiffness scaled down by the same
/// factor, so hard stays as much harder than soft.
pub const STIFFEST_COPY_N_PER_M: f32 = 1000.0;
/// With proxy rendering, a copy whose briefed stiffness is above this (N/m, before the device's scaling)
/// feels hard: halfway between the soft and the hard materials (300 and 800: 550).
pub fn hard_above_n_per_m() -> f32 {
    let stiffness = |c: artifact::MaterialClass| c.material().stiffness_n_per_m;
    0.5 * (stiffness(artifact::MaterialClass::SoftSmooth) + stiffness(artifact::MaterialClass::HardSmooth))
}

/// [`hard_above_n_per_m`] scaled to the device when the proxy renders, else `None`.
pub(crate) fn proxy_hard_above(rendering: Rendering, stiffness_scale: f32) -> Option<f32> {
    (rendering == Rendering::Proxy).then(|| hard_above_n_per_m() * stiffness_scale)
}

/// How forces are rendered.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderingChoice {
    /// By the device: the 3-DOF proxy when it renders no torque, else volumetric.
    #[default]
    Auto,
    /// The gemstone's inner spheres against the copy's (force and torque, through a virtual coupling).
    Volumetric,
    /// The 3-DOF god-object: the stylus tip held on the copy's surface (force only).
    Proxy,
}

/// How the haptic side is set up.
#[derive(Resource, Clone, Debug)]
pub struct HapticsSettings {
    /// The device (default sim).
    pub device: DeviceChoice,
    /// Device preset the sim device copies (default the Phantom Desktop).
    pub preset: Option<String>,
    /// Record the device's ticks to this trace file (default none).
    pub record: Option<PathBuf>,
    /// How forces are rendered (default: by the device).
    pub rendering: RenderingChoice,
    /// Spheres per copy's tree (default 3000).
    pub spheres: usize,
    /// Where built trees are cached (default none).
    pub cache_dir: Option<PathBuf>,
    /// Real-time priority for the haptic thread (default none).
    pub realtime_priority: Option<i32>,
}

impl Default for HapticsSettings {
    fn default() -> Self {
        Self {
            device: DeviceChoice::Sim,
            preset: None,
            record: None,
            rendering: RenderingChoice::Auto,
            spheres: 3000,
            cache_dir: None,
            realtime_priority: None,
        }
    }
}

/// The copy being felt.
#[derive(Clone, Debug, PartialEq)]
pub struct OnBench {
    /// The copy.
    pub item: ItemId,
    /// The haptic clock when its tree reached the collision thread, µs.
    pub since_us: u64,
    /// Spheres in its tree.
    pub spheres: usize,
    /// Whether the tree came from the cache.
    pub cached: bool,
    /// Bytes of the copy's surface grid; `None` without one (proxy rendering).
    pub surface_bytes: Option<usize>,
}

/// One second of the haptic and collision loops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateWindow {
    /// Start of the window on the haptic clock, µs.
    pub start_us: u64,
    /// Haptic ticks in the window per second, Hz.
    pub haptic_hz: u32,
    /// Collision steps in the window per second, Hz.
    pub collision_hz: u32,
    /// Whether a copy was on the bench for the whole window.
    pub with_copy: bool,
}

/// What the worker sends back for a copy, or why it could not.
pub struct BuiltCopy {
    /// The copy's tree.
    pub tree: InnerSphereTree,
    /// Whether the tree came from the cache.
    pub cached: bool,
    /// The copy's surface, with volumetric rendering.
    pub surface: Option<SignedDistanceGrid>,
}

/// What the worker sends back: the copy built, or why not.
pub type Built = Result<BuiltCopy, String>;

/// Builds (or loads) the tree of `mesh`, and its surface grid when `with_surface`.
pub fn build_copy(mesh: &HapticMesh, spheres: usize, cache: Option<&std::path::Path>, with_surface: bool) -> Built {
    let (tree, cached) = build_tree(mesh, spheres, cache)?;
    let surface = with_surface.then(|| surface_grid(mesh, spheres)).transpose()?;
    Ok(BuiltCopy { tree, cached, surface })
}

/// The gemstone tool and the rig's configuration for a device: what the running client's haptics
/// ([`crate::bench::add_haptics`], through `bevy_haptics`) and the lockstep rig
/// ([`crate::touch_bench::LockstepHaptics`]) both start from.
pub(crate) struct RigSetup {
    /// The gemstone.
    pub tool: ToolSpec,
    /// The rig's configuration.
    pub config: RigConfig,
    /// How forces are rendered (the choice resolved for the device).
    pub rendering: Rendering,
    /// With proxy rendering, what every copy's stiffness is scaled by to fit the device.
    pub stiffness_scale: f32,
    /// Device frame to scene.
    pub map: WorkspaceMap,
    /// The gem's packed volume [`REFERENCE_DEPTH_M`] deep in a flat face, m³.
    pub tool_reference_volume_m3: f32,
}

impl RigSetup {
    /// The gemstone's tree, the rendering the settings choose for `specs` and the proxy's spring scaled
    /// to the device.
    pub fn new(specs: &DeviceSpecs, settings: &HapticsSettings) -> Result<Self, ClientError> {
        let gem = collette::scene::brilliant_cut(TOOL_DIAMETER_M);
        let (tree, _) = collette::build(&gem, &BuildOptions::spheres(TOOL_SPHERES), &mut |_| {})
            .map_err(|e| ClientError::Device(format!("building the gemstone's tree: {e}")))?;
        let tool_reference_volume_m3 =
            immersed_volume(tree.spheres(), tree.weights(), glam::Vec3::X, REFERENCE_DEPTH_M);
        // The gem is far stiffer than any copy, and its friction is 1 so the copy's own coefficient decides
        // (see `haptic_material`).
        let tool = ToolSpec::new(Arc::new(tree), ForceComponent::rigid_tool().material());
        let scale = if specs.workspace_radius_m > 0.0 { (0.08 / specs.workspace_radius_m).max(1.0) } else { 1.0 };
        let map = WorkspaceMap { origin: Pose::IDENTITY, scale };
        let rendering = match settings.rendering {
            RenderingChoice::Volumetric => Rendering::Coupled,
            RenderingChoice::Proxy => Rendering::Proxy,
            RenderingChoice::Auto if specs.renders_torque() => Rendering::Coupled,
            RenderingChoice::Auto => Rendering::Proxy,
        };
        let stiffness_scale = (specs.max_stiffness_n_per_m / STIFFEST_COPY_N_PER_M).clamp(f32::MIN_POSITIVE, 1.0);
        // The proxy's spring is ε_c × this: the briefed stiffness (see `haptic_material`), scaled to the device.
        let proxy = ProxyRendering {
            volume_per_depth_m2: tool_reference_volume_m3 / REFERENCE_DEPTH_M * stiffness_scale,
            ..ProxyRendering::default()
        };
        let mut config = RigConfig { map, rendering, proxy, ..RigConfig::default() };
        config.haptic.realtime_priority = settings.realtime_priority;
        config.collision.realtime_priority = settings.realtime_priority.map(|p| (p - 1).max(1));
        Ok(Self { tool, config, rendering, stiffness_scale, map, tool_reference_volume_m3 })
    }
}

/// The contact material of a copy: the briefed stiffness `k` (N/m) becomes the volumetric stiffness
/// that pushes back `k · d0` when the gemstone is `d0` = [`REFERENCE_DEPTH_M`] deep in a flat, fully
/// packed face, where its weighted volume is `tool_volume_m3` (see [`immersed_volume`]). Friction is
/// squared because contact friction is the geometric mean with the gem's (1). Ridges become a texture
/// repeating up the copy (+Y), their depth read with the briefed stiffness.
pub fn haptic_material(m: &artifact::Material, tool_volume_m3: f32) -> ForceComponent {
    ForceComponent {
        stiffness_n_per_m3: m.stiffness_n_per_m * REFERENCE_DEPTH_M / tool_volume_m3.max(1e-12),
        damping_ns_per_m: m.damping,
        friction: m.friction * m.friction,
        ridges: m.ridges.map(|r| Ridges {
            spacing_m: r.spacing_m,
            depth_m: r.depth_m,
            stiffness_n_per_m: m.stiffness_n_per_m,
        }),
        force_scale: 1.0,
    }
}

/// Volume of `spheres` past a plane `depth` behind their outermost point along `normal` (what of a
/// tool is inside a flat face it was pushed `depth` into, along −`normal`), each sphere's part times
/// its weight (the share of the mesh it stands for, as the overlap queries count it), m³.
pub fn immersed_volume(spheres: &[collette::Sphere], weights: &[f32], normal: Vec3, depth: f32) -> f32 {
    let n = normal.normalize_or(Vec3::X);
    let front = spheres.iter().map(|s| s.center.dot(n) + s.radius).fold(f32::NEG_INFINITY, f32::max);
    let plane = front - depth;
    spheres
        .iter()
        .zip(weights.iter().chain(std::iter::repeat(&1.0)))
        .map(|(s, w)| {
            let h = (s.center.dot(n) + s.radius - plane).clamp(0.0, 2.0 * s.radius);
            w * std::f32::consts::PI * h * h * (3.0 * s.radius - h) / 3.0
        })
        .sum()
}

/// Content hash of a mesh and the build settings, as the cache file's name.
pub fn cache_key(mesh: &HapticMesh, spheres: usize) -> String {
    let mut h = blake3::Hasher::new();
    h.update(b"phantom-heist ist v4"); // v2: weighted spheres; v3: past the surface; v4: power-diagram weights
    h.update(&(spheres as u64).to_le_bytes());
    for v in &mesh.vertices {
        for c in v {
            h.update(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            h.update(&i.to_le_bytes());
        }
    }
    h.finalize().to_hex()[..32].to_owned()
}

/// The signed distance grid of `mesh`'s surface, as fine as the packing grid of a tree of `spheres`
/// (quick to build, so not cached: about 0.6 s for an idol on two cores, 13 MB).
pub fn surface_grid(mesh: &HapticMesh, spheres: usize) -> Result<SignedDistanceGrid, String> {
    let resolution = BuildOptions::spheres(spheres).resolution();
    SignedDistanceGrid::new(&tri_mesh(mesh)?, resolution).map_err(|e| format!("its surface grid: {e}"))
}

fn tri_mesh(mesh: &HapticMesh) -> Result<TriMesh, String> {
    let vertices = mesh.vertices.iter().map(|v| Vec3::from_array(*v)).collect();
    TriMesh::new(vertices, mesh.triangles.clone()).map_err(|e| format!("its mesh is not a closed surface: {e}"))
}

/// Builds (or loads) the tree of `mesh`; the flag tells whether it came from `cache`.
pub fn build_tree(
    mesh: &HapticMesh,
    spheres: usize,
    cache: Option<&std::path::Path>,
) -> Result<(InnerSphereTree, bool), String> {
    let file = cache.map(|dir| dir.join(format!("{}.ist", cache_key(mesh, spheres))));
    if let Some(file) = &file
        && file.exists()
    {
        match InnerSphereTree::load(file) {
            Ok(tree) => return Ok((tree, true)),
            Err(e) => log::warn!("ignoring the cached tree {}: {e}", file.display()),
        }
    }
    let (tree, _) =
        collette::build(&tri_mesh(mesh)?, &BuildOptions::spheres(spheres), &mut |_| {}).map_err(|e| e.to_string())?;
    if let Some(file) = &file {
        let saved = file.parent().map_or(Ok(()), std::fs::create_dir_all).map_err(|e| e.to_string());
        if let Err(e) = saved.and_then(|()| tree.save(file).map_err(|e| e.to_string())) {
            log::warn!("could not cache the tree in {}: {e}", file.display());
        }
    }
    Ok((tree, false))
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::artifact::{ArtifactKind, MaterialClass, build_mesh, generate_copies};

    #[test]
    fn the_proxys_hardness_threshold_lies_between_every_soft_and_every_hard_material() {
        let t = hard_above_n_per_m();
        for c in MaterialClass::ALL {
            let k = c.material().stiffness_n_per_m;
            assert!(if c.is_hard() { k > t + 100.0 } else { k < t - 100.0 }, "{c:?}: {k} N/m against {t}");
        }
    }

    #[test]
    fn a_hard_copy_pushes_back_its_briefed_stiffness_at_the_reference_depth() {
        // A single sphere: the immersed volume is a cap.
        let r = TOOL_DIAMETER_M / 2.0;
        let d = REFERENCE_DEPTH_M;
        let one = [collette::Sphere { center: Vec3::ZERO, radius: r }];
        let cap = std::f32::consts::PI * d * d * (3.0 * r - d) / 3.0;
        assert!((immersed_volume(&one, &[1.0], Vec3::X, d) / cap - 1.0).abs() < 1e-4);
        assert!((immersed_volume(&one, &[1.5], Vec3::X, d) / (1.5 * cap) - 1.0).abs() < 1e-4, "weighted");
        assert!(
            (immersed_volume(&one, &[1.0], Vec3::X, 3.0 * r) / (4.0 / 3.0 * std::f32::consts::PI * r * r * r) - 1.0)
                .abs()
                < 1e-4
        );
        let m = haptic_material(&MaterialClass::HardRough.material(), cap).material();
        let force = m.stiffness_n_per_m3 * cap;
        assert!((force / (800.0 * d) - 1.0).abs() < 1e-4, "{force} N at {d} m");
        let soft = haptic_material(&MaterialClass::SoftRough.material(), cap).material();
        assert!((m.stiffness_n_per_m3 / soft.stiffness_n_per_m3 - 800.0 / 300.0).abs() < 1e-3);
        let contact = m.combine(&ForceComponent::rigid_tool().material());
        assert!((contact.friction - 0.6).abs() < 1e-4);
        // The rough copy's ridges reach the contact, read with its briefed stiffness; a smooth copy has none.
        let ridges = contact.texture.expect("a rough copy is ribbed");
        assert_eq!((ridges.spacing, ridges.amplitude, ridges.stiffness, ridges.axis), (0.003, 0.0003, 800.0, Vec3::Y));
        assert!(haptic_material(&MaterialClass::HardSmooth.material(), cap).ridges.is_none());
    }

    #[test]
    fn a_tree_is_cached_by_content_and_loaded_again() {
        let dir = std::env::temp_dir().join(format!("phantom-cache-{}", std::process::id()));
        let (copies, _) = generate_copies(ArtifactKind::Idol, 3, 3);
        let mesh = build_mesh(&copies[0], 3);
        let (built, cached) = build_tree(&mesh, 300, Some(&dir)).expect("builds");
        assert!(!cached);
        let (loaded, cached) = build_tree(&mesh, 300, Some(&dir)).expect("loads");
        assert!(cached, "the second build comes from the cache");
        assert_eq!(built.spheres().len(), loaded.spheres().len());
        let differs =
            copies.iter().find(|c| c.feature_count != copies[0].feature_count).expect("a fake with another count");
        let other = build_mesh(differs, 3);
        assert_ne!(cache_key(&mesh, 300), cache_key(&other, 300));
        assert_ne!(cache_key(&mesh, 300), cache_key(&mesh, 301));
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_copys_surface_grid_is_as_fine_as_its_packing_and_signs_inside_and_out() {
        let (copies, _) = generate_copies(ArtifactKind::Idol, 3, 3);
        let mesh = build_mesh(&copies[0], 3);
        let grid = surface_grid(&mesh, 3000).expect("builds");
        let bounds = tri_mesh(&mesh).expect("a closed mesh").aabb();
        let longest = bounds.extents().max_element();
        assert_eq!(BuildOptions::spheres(3000).resolution(), 100);
        assert!((grid.voxel_size() * 100.0 / longest - 1.0).abs() < 1e-4, "voxel {}", grid.voxel_size());
        // The idol stands on its base, centred on its axis: its middle is inside, beside it is not.
        let middle = bounds.center();
        assert!(grid.distance(middle) > 0.0, "inside: {}", grid.distance(middle));
        let beside = middle + Vec3::X * longest;
        assert!(grid.distance(beside) < -0.5 * longest, "outside: {}", grid.distance(beside));
        // 16 bytes a point (distance, gradient) and the slope pyramid's byte a cell, a seventh more above.
        let points = grid.dims().iter().product::<usize>();
        assert!((16 * points..=(16 * points + points * 8 / 7 + 64)).contains(&grid.memory_bytes()));
        let broken =
            HapticMesh { vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], triangles: vec![[0, 1, 2]] };
        assert!(surface_grid(&broken, 3000).expect_err("refused").contains("not a closed surface"));
    }

    #[test]
    fn a_broken_mesh_is_refused_with_the_reason() {
        let mesh =
            HapticMesh { vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], triangles: vec![[0, 1, 2]] };
        let err = build_tree(&mesh, 100, None).expect_err("refused");
        assert!(err.contains("not a closed surface"), "{err}");
    }
}
