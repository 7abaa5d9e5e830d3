//! Shapes: spheres (with the exact lens of two spheres), validated closed triangle meshes, their
//! signed distance grids and their split surfaces (shells).
//!
//! You need this module to load the mesh you want to pack, or to compute sphere-sphere overlaps yourself.

mod distance_grid;
mod mesh;
mod primitives;
mod shell;
mod solid;
mod sphere;

pub use distance_grid::SignedDistanceGrid;
pub use mesh::TriMesh;
pub use primitives::{box_buffers, torus_buffers, uv_sphere_buffers};
pub(crate) use shell::ShellNode;
pub use shell::SurfaceShell;
pub use solid::Solid;
pub use sphere::{Lens, Sphere, lens, lens_volume, sphere_volume};
pub(crate) use sphere::{Lens4, cap_moment, cap_volume, lens_x4};
