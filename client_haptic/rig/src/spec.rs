//! What the game gives the rig: the tool and the watched objects, with their trees and materials.
//!
//! You need this module to describe a scene to a [`HapticRig`](crate::HapticRig) or a
//! [`Lockstep`](crate::lockstep::Lockstep).

use std::sync::Arc;

use forcecomp::Material;
use glam::Vec3;
use haptic_common::Pose;

/// Most objects watched at once (all against the tool: the collision thread's broad phase queries only
/// those whose bounds touch the tool's).
pub const MAX_OBJECTS: usize = 256;

/// Most watchers between two objects at once (besides the tool's against every object).
pub const MAX_PAIR_WATCHERS: usize = 1024;

/// What a watcher between two objects saw on the collision thread's latest step (objects do not push
/// each other: this is what the game learns of their contact).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairContact {
    /// The first object's id.
    pub a: u32,
    /// The second object's id.
    pub b: u32,
    /// Whether their trees overlap.
    pub touching: bool,
    /// Overlapping sphere pairs found.
    pub pairs: u32,
    /// Their overlap volume, m³.
    pub volume_m3: f32,
    /// The collision step that measured it (0: none yet).
    pub sequence: u64,
}

/// The tool: its Inner Sphere Tree, centre of mass and material.
#[derive(Clone, Debug)]
pub struct ToolSpec {
    /// The tree, in the tool's frame (scene units).
    pub tree: Arc<collette::InnerSphereTree>,
    /// Centre of mass in the tool's frame.
    pub center_of_mass: Vec3,
    /// Material.
    pub material: Material,
    /// Its surface, split from the mesh its tree was built from: against an object with a surface grid
    /// the tool's surface is measured instead of its spheres (exact on flat faces at any depth, see
    /// [`ToolSpec::with_shell`]). `None`: its spheres.
    pub shell: Option<Arc<collette::SurfaceShell>>,
    /// Its own surface grid (with a shell): against an object that has a shell and a grid too, both
    /// surfaces are measured (see [`ToolSpec::with_surface`]). `None`: its shell's columns alone.
    pub surface: Option<Arc<collette::SignedDistanceGrid>>,
}

impl ToolSpec {
    /// A tool whose centre of mass is the volume-weighted centre of its inner spheres.
    pub fn new(tree: Arc<collette::InnerSphereTree>, material: Material) -> Self {
        let center_of_mass = center_of_mass(&tree);
        Self { tree, center_of_mass, material, shell: None, surface: None }
    }

    /// The same tool with its surface shell (`SurfaceShell::new(&mesh, max_edge)` of the mesh its tree
    /// was built from; 0.5 mm edges against grids of 0.5–1.5 mm voxels): against an object that has a
    /// surface grid ([`crate::HapticRig::set_surface`]), the force is then the column of the object's
    /// inside under every piece of the tool's surface (`collette::overlap_shell`), which the fidelity
    /// benchmark finds exact on flat faces and edges down to 0.1 mm (docs/haptics.md).
    pub fn with_shell(mut self, shell: Arc<collette::SurfaceShell>) -> Self {
        self.shell = Some(shell);
        self
    }

    /// The same tool with its surface grid too (`SignedDistanceGrid::new(&mesh, resolution)` of the
    /// same mesh; with its shell, [`ToolSpec::with_shell`]): against an object that has a shell and a
    /// grid ([`crate::HapticRig::set_object_shell`], [`crate::HapticRig::set_surface`]) the collision
    /// thread then measures both surfaces, the overlap's whole boundary (`collette::overlap_surfaces`),
    /// right however deep the tool goes: past the middle of a thin part of the object the shell's
    /// columns alone run to its far face and measure too little. It costs about three times the columns;
    /// a step cut short by its time budget falls back on the columns.
    pub fn with_surface(mut self, grid: Arc<collette::SignedDistanceGrid>) -> Self {
        self.surface = Some(grid);
        self
    }
}

/// A watched object.
#[derive(Clone, Debug)]
pub struct ObjectSpec {
    /// Id chosen by the game (reported in contacts).
    pub id: u32,
    /// The tree, in the object's frame.
    pub tree: Arc<collette::InnerSphereTree>,
    /// Pose in the scene.
    pub pose: Pose,
    /// Material.
    pub material: Material,
}

/// Centre of a tree's inner spheres weighted by the mesh volume each stands for (the object's centre
/// of mass at uniform density).
pub fn center_of_mass(tree: &collette::InnerSphereTree) -> Vec3 {
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
    for (s, share) in tree.spheres().iter().zip(tree.weights()) {
        let w = s.radius * s.radius * s.radius * share;
        sum += s.center * w;
        weight += w;
    }
    if weight > 0.0 { sum / weight } else { Vec3::ZERO }
}
