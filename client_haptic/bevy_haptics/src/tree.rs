//! Sphere trees as Bevy assets: loaded from `.ist` files, built from `.obj` meshes by the asset loader, or
//! built from a Bevy [`Mesh`] on the async compute pool (`mesh_build`) — never on the game thread.
//!
//! You need this module to give a [`HapticTool`](crate::HapticTool) or a
//! [`HapticCollider`](crate::HapticCollider) its tree: `asset_server.load("meshes/bunny.obj")` (with
//! [`SphereTreeSettings`] for its sphere count and scale), `asset_server.load("bunny.ist")` (a tree built
//! beforehand with the `collette` tool), or a [`SphereTreeFromMesh`](crate::SphereTreeFromMesh) beside the entity's `Mesh3d`.

use std::sync::Arc;

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext};
use bevy::mesh::{Indices, Mesh, VertexAttributeValues};
use bevy::prelude::*;
use collette::{BuildOptions, InnerSphereTree, SignedDistanceGrid, Sphere, SurfaceShell, TriMesh};
use serde::{Deserialize, Serialize};

/// An Inner Sphere Tree: the spheres packed inside a closed mesh, in the mesh's frame (metres), as the
/// collision thread measures it (the paper's sphere-tree asset); optionally with the mesh's surface as a
/// signed distance grid, against which volumetric rendering measures the tool's spheres (the overlap
/// within about 1 % of the true one, and no bumps of the packing under a smooth surface); and
/// optionally with its surface shell: a tool's is measured instead of its spheres against a collider's
/// grid (exact on flat faces at any depth, a box's corner too), and when the tool and the collider
/// both have a shell and a grid, both surfaces are (the overlap's whole boundary: right past the
/// middle of a collider's thin parts too).
#[derive(Asset, TypePath, Clone, Debug)]
pub struct SphereTree {
    /// The tree.
    pub tree: Arc<InnerSphereTree>,
    /// The mesh's surface, in the same frame (`None`: the tree's spheres stand for it).
    pub surface: Option<Arc<SignedDistanceGrid>>,
    /// The mesh's surface split into small triangles, in the same frame: used when this tree is the
    /// tool's and the collider it touches has a `surface` (`None`: the tool's spheres are measured),
    /// and a collider's when the tool has a shell and a `surface` too (both surfaces measured).
    pub shell: Option<Arc<SurfaceShell>>,
}

impl SphereTree {
    /// A tree built elsewhere (with collette).
    pub fn new(tree: InnerSphereTree) -> Self {
        Self { tree: Arc::new(tree), surface: None, shell: None }
    }

    /// This tree with `surface` (a grid of the same mesh, built with collette's
    /// [`SignedDistanceGrid::new`]: about half a second for 100 voxels along the longest side).
    pub fn with_surface(mut self, surface: SignedDistanceGrid) -> Self {
        self.surface = Some(Arc::new(surface));
        self
    }

    /// This tree with `shell` (collette's [`SurfaceShell::new`] of the same mesh, e.g. 0.5 mm edges:
    /// milliseconds for a 1 cm gem): a tool's surface is measured instead of its spheres against a
    /// collider with a surface grid (docs/haptics.md, *Fidelity against exact answers*; it costs more on
    /// deep contacts: about 0.5 ms for a 1 cm gem 5 mm in); a tool with a shell and a surface grid
    /// against a collider with both measures both surfaces (about 0.25 ms for the gem 1 mm in, 1.2 ms
    /// 5 mm in, where a collision step's budget falls back on the tool's surface alone).
    pub fn with_shell(mut self, shell: SurfaceShell) -> Self {
        self.shell = Some(Arc::new(shell));
        self
    }

    /// This tree with its mesh's surfaces, built from `mesh` (the one the tree was packed into, in the
    /// same frame): a surface grid of `grid_voxels` along the mesh's longest side (0: none; see
    /// [`with_surface`](Self::with_surface)) and a shell of edges at most `shell_edge_m` (0: none; not a
    /// positive length: an error; see [`with_shell`](Self::with_shell)). With both on the tool and on a collider, both surfaces are
    /// measured. Takes about a second for the bunny at 128 voxels and 1 mm edges: off the game thread.
    pub fn with_surfaces_of(
        mut self,
        mesh: &TriMesh,
        grid_voxels: usize,
        shell_edge_m: f32,
    ) -> Result<Self, SphereTreeError> {
        let failed = |e: collette::BuildError| SphereTreeError::Build(e.to_string());
        if grid_voxels > 0 {
            self = self.with_surface(SignedDistanceGrid::new(mesh, grid_voxels).map_err(failed)?);
        }
        if shell_edge_m != 0.0 {
            self = self.with_shell(SurfaceShell::new(mesh, shell_edge_m).map_err(failed)?);
        }
        Ok(self)
    }

    /// One sphere of `radius_m` at the origin: a ball tip.
    pub fn ball(radius_m: f32) -> Self {
        let r = radius_m.max(1e-6);
        let volume = 4.0 / 3.0 * std::f32::consts::PI * r * r * r;
        Self::new(InnerSphereTree::from_spheres(vec![Sphere { center: Vec3::ZERO, radius: r }], volume))
    }

    /// A brilliant-cut gemstone `diameter_m` wide (its table up, +Y), packed with `spheres` spheres: the
    /// paper's tool. Takes a few milliseconds for a few hundred spheres.
    pub fn gem(diameter_m: f32, spheres: usize) -> Result<Self, SphereTreeError> {
        Self::build(&collette::scene::brilliant_cut(diameter_m), spheres)
    }

    /// Packs `spheres` spheres into `mesh` (takes milliseconds to seconds: call it off the game thread).
    pub fn build(mesh: &TriMesh, spheres: usize) -> Result<Self, SphereTreeError> {
        let (tree, _) = collette::build(mesh, &BuildOptions::spheres(spheres.max(1)), &mut |_| {})
            .map_err(|e| SphereTreeError::Build(e.to_string()))?;
        Ok(Self::new(tree))
    }

    /// Packs `spheres` spheres into a Bevy mesh (vertices times `scale`, to metres; see [`tri_mesh`]).
    /// Takes milliseconds to seconds: call it off the game thread, or use
    /// [`SphereTreeFromMesh`](crate::SphereTreeFromMesh).
    pub fn from_mesh(mesh: &Mesh, scale: f32, spheres: usize) -> Result<Self, SphereTreeError> {
        Self::build(&tri_mesh(mesh, scale)?, spheres)
    }

    /// Writes the tree as an `.ist` file (what the asset loader and the `collette` tool read).
    pub fn save(&self, path: impl AsRef<std::path::Path>) -> Result<(), SphereTreeError> {
        Ok(self.tree.save(path)?)
    }

    /// Number of inner spheres.
    pub fn len(&self) -> usize {
        self.tree.spheres().len()
    }

    /// True for a tree without spheres.
    pub fn is_empty(&self) -> bool {
        self.tree.spheres().is_empty()
    }
}

/// Why a sphere tree could not be loaded or built.
#[derive(Debug, thiserror::Error)]
pub enum SphereTreeError {
    /// The file could not be read.
    #[error("reading it: {0}")]
    Io(#[from] std::io::Error),
    /// The `.ist` file is not a sphere tree.
    #[error("not a sphere tree file: {0}")]
    Ist(#[from] collette::IstFileError),
    /// The mesh is not something spheres can be packed into (not closed, no triangles, ...).
    #[error("its mesh: {0}")]
    Mesh(String),
    /// Packing failed.
    #[error("packing its spheres: {0}")]
    Build(String),
}

/// How the loader builds a tree from an `.obj` mesh (ignored for `.ist` files, which hold a built tree).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct SphereTreeSettings {
    /// Spheres to pack (default 2,000).
    pub spheres: usize,
    /// The mesh's vertices are multiplied by this, to metres (default 1).
    pub scale: f32,
    /// Voxels of its surface grid along the mesh's longest side (default 0: no grid; 100–150 for a
    /// collider, see [`SphereTree::with_surface`]).
    #[serde(default)]
    pub surface_voxels: usize,
    /// Longest edge of its surface shell, m (default 0: no shell; 0.5–1 mm, see
    /// [`SphereTree::with_shell`]).
    #[serde(default)]
    pub shell_edge_m: f32,
}

impl Default for SphereTreeSettings {
    fn default() -> Self {
        Self { spheres: 2_000, scale: 1.0, surface_voxels: 0, shell_edge_m: 0.0 }
    }
}

/// Loads `.ist` files and builds trees from `.obj` meshes (on Bevy's asset threads).
#[derive(Default, TypePath)]
pub struct SphereTreeLoader;

impl AssetLoader for SphereTreeLoader {
    type Asset = SphereTree;
    type Settings = SphereTreeSettings;
    type Error = SphereTreeError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        settings: &SphereTreeSettings,
        context: &mut LoadContext<'_>,
    ) -> Result<SphereTree, SphereTreeError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        let is_obj = context.path().path().extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if !is_obj {
            return Ok(SphereTree::new(InnerSphereTree::from_bytes(&bytes)?));
        }
        let mesh = TriMesh::from_obj_bytes(&bytes, context.path().path())
            .and_then(|m| m.map_vertices(|v| v * settings.scale))
            .map_err(|e| SphereTreeError::Mesh(e.to_string()))?;
        SphereTree::build(&mesh, settings.spheres)?.with_surfaces_of(
            &mesh,
            settings.surface_voxels,
            settings.shell_edge_m,
        )
    }

    fn extensions(&self) -> &[&str] {
        &["ist", "obj"]
    }
}

/// The closed triangle mesh of a Bevy [`Mesh`] (positions as `Float32x3`, any indices), scaled.
/// Vertices at the same place (within 1 µm) are merged first: Bevy's shapes repeat a corner for each
/// face it belongs to (for its normals), which would leave every edge open.
pub fn tri_mesh(mesh: &Mesh, scale: f32) -> Result<TriMesh, SphereTreeError> {
    let Some(VertexAttributeValues::Float32x3(positions)) = mesh.attribute(Mesh::ATTRIBUTE_POSITION) else {
        return Err(SphereTreeError::Mesh("it has no Float32x3 positions".into()));
    };
    let indices: Vec<u32> = match mesh.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&i| u32::from(i)).collect(),
        Some(Indices::U32(i)) => i.clone(),
        None => (0..positions.len() as u32).collect(),
    };
    let mut welded: Vec<Vec3> = Vec::with_capacity(positions.len());
    let mut slots = std::collections::HashMap::with_capacity(positions.len());
    let remap: Vec<u32> = positions
        .iter()
        .map(|p| {
            let v = Vec3::from_array(*p) * scale;
            let key = (v * 1e6).round().as_ivec3().to_array();
            *slots.entry(key).or_insert_with(|| {
                welded.push(v);
                (welded.len() - 1) as u32
            })
        })
        .collect();
    let mut triangles = Vec::with_capacity(indices.len() / 3);
    for t in indices.chunks(3) {
        let corner = |i: u32| {
            remap.get(i as usize).copied().ok_or_else(|| SphereTreeError::Mesh(format!("index {i} has no vertex")))
        };
        let [a, b, c] =
            [corner(t[0])?, corner(*t.get(1).unwrap_or(&u32::MAX))?, corner(*t.get(2).unwrap_or(&u32::MAX))?];
        // A triangle whose corners merged into fewer than three has no area.
        if a != b && b != c && a != c {
            triangles.push([a, b, c]);
        }
    }
    TriMesh::new(welded, triangles).map_err(|e| SphereTreeError::Mesh(e.to_string()))
}
