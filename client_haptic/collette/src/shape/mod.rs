//! Shapes: spheres (with the exact lens of two spheres) and validated closed triangle meshes.
//!
//! You need this module to load the mesh you want to pack, or to compute sphere-sphere overlaps yourself.

mod mesh;
mod primitives;
mod sphere;

pub use mesh::TriMesh;
pub use primitives::{box_buffers, torus_buffers, uv_sphere_buffers};
pub use sphere::{Lens, Sphere, lens, lens_volume, sphere_volume};
pub(crate) use sphere::{Lens4, lens_x4};
