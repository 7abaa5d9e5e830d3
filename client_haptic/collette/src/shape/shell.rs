//! A closed mesh's surface as small triangles under a tree of bounding spheres: the tool's side of
//! [`overlap_shell`](crate::query::overlap_shell).
//!
//! You need this module when a tool's force against an object with a surface grid should be exact on
//! flat faces at any depth: the tool's surface, not its sphere packing, is measured against the
//! object's distance (docs/collette.md, *The tool's surface against the touched object's surface*).

use crate::error::BuildError;
use crate::shape::TriMesh;
use glam::Vec3;

/// The surface of a closed mesh, its triangles split until no edge is longer than a chosen length (so
/// the object's distance, read at the corners, is nearly linear over each), in the leaves of a binary
/// tree of bounding spheres. Metres and frame of the mesh.
#[derive(Clone, Debug)]
pub struct SurfaceShell {
    /// Corners of the triangles, counter-clockwise seen from outside, in the leaves' order.
    triangles: Vec<[Vec3; 3]>,
    /// Each triangle's corners as indices into its leaf's corners (`leaf_corners`), so a query reads the
    /// object's distance once at a corner its leaf's triangles share.
    corner_of: Vec<[u8; 3]>,
    /// The distinct corners of each leaf's triangles, leaf after leaf.
    leaf_corners: Vec<Vec3>,
    nodes: Vec<ShellNode>,
    max_edge: f32,
}

/// One node of the shell's tree: a bounding sphere of its triangles, and either its two children
/// (`first`, `first + 1` in `nodes`) or its triangles (`first .. first + count`).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ShellNode {
    pub(crate) center: Vec3,
    pub(crate) radius: f32,
    pub(crate) first: u32,
    /// Triangles of a leaf; 0 for an inner node.
    pub(crate) count: u32,
    /// A leaf's distinct corners: `corners .. corners + corner_count` in `leaf_corners`.
    pub(crate) corners: u32,
    pub(crate) corner_count: u32,
}

impl SurfaceShell {
    /// Most triangles a shell may hold after splitting.
    pub const MAX_TRIANGLES: usize = 4_000_000;
    /// Most triangles in one leaf of the tree.
    const LEAF: usize = 8;
    /// Most distinct corners a leaf can have.
    pub(crate) const LEAF_CORNERS: usize = 3 * Self::LEAF;

    /// Splits `mesh`'s triangles (each at the middle of its longest edge, again and again) until no
    /// edge is longer than `max_edge` (m; about the touched objects' grid voxel: 1 mm for a 10 cm
    /// object at 128 voxels) and puts them in a tree. Errors when `max_edge` is not a positive length
    /// or the split would exceed [`Self::MAX_TRIANGLES`].
    pub fn new(mesh: &TriMesh, max_edge: f32) -> Result<Self, BuildError> {
        if !(max_edge.is_finite() && max_edge > 0.0) {
            return Err(BuildError::InvalidOption(format!("shell edge length {max_edge} m is not a positive length")));
        }
        let vertices = mesh.vertices();
        let too_many = || {
            BuildError::InvalidOption(format!(
                "a shell with edges of at most {max_edge} m would exceed {} triangles",
                Self::MAX_TRIANGLES
            ))
        };
        // A triangle with no edge over `max_edge` has at most (√3/4)·max_edge² of area.
        let area: f32 = mesh
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        if area / (0.433 * max_edge * max_edge) > Self::MAX_TRIANGLES as f32 {
            return Err(too_many());
        }
        let mut triangles = Vec::with_capacity(mesh.triangles().len());
        let mut todo: Vec<[Vec3; 3]> = Vec::new();
        for t in mesh.triangles() {
            todo.push(t.map(|i| vertices[i as usize]));
            while let Some(tri) = todo.pop() {
                let edges = [tri[0].distance(tri[1]), tri[1].distance(tri[2]), tri[2].distance(tri[0])];
                let (longest, length) =
                    edges.iter().copied().enumerate().fold((0, 0.0f32), |m, (i, e)| if e > m.1 { (i, e) } else { m });
                if length <= max_edge {
                    if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length_squared() > 0.0 {
                        triangles.push(tri);
                    }
                    continue;
                }
                if triangles.len() + todo.len() + 2 > Self::MAX_TRIANGLES {
                    return Err(too_many());
                }
                // Split edge (a, b) at its middle m: (a, m, c) and (m, b, c) keep the orientation.
                let (a, b, c) = (tri[longest], tri[(longest + 1) % 3], tri[(longest + 2) % 3]);
                let m = (a + b) * 0.5;
                todo.push([a, m, c]);
                todo.push([m, b, c]);
            }
        }
        if triangles.is_empty() {
            return Err(BuildError::InvalidOption("the mesh has no triangle with an area to make a shell of".into()));
        }
        let mut nodes = Vec::with_capacity(2 * triangles.len() / Self::LEAF + 2);
        nodes.push(ShellNode::default());
        let mut pending = vec![(0usize, 0usize, triangles.len())];
        while let Some((node, start, end)) = pending.pop() {
            let part = &mut triangles[start..end];
            let (low, high) =
                part.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let center = (low + high) * 0.5;
            let radius = part.iter().flatten().map(|p| p.distance(center)).fold(0.0f32, f32::max);
            if part.len() <= Self::LEAF {
                nodes[node] =
                    ShellNode { center, radius, first: start as u32, count: part.len() as u32, ..ShellNode::default() };
                continue;
            }
            // Halve along the longest side of the centroids' box.
            let centroid = |t: &[Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
            let (clo, chi) = part
                .iter()
                .map(centroid)
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
            let extent = chi - clo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let half = part.len() / 2;
            part.select_nth_unstable_by(half, |p, q| centroid(p)[axis].total_cmp(&centroid(q)[axis]));
            let first = nodes.len();
            nodes.extend([ShellNode::default(); 2]);
            nodes[node] = ShellNode { center, radius, first: first as u32, ..ShellNode::default() };
            pending.push((first, start, start + half));
            pending.push((first + 1, start + half, end));
        }
        // Each leaf's distinct corners (a split edge's middle is the same float from either side).
        let (mut corner_of, mut leaf_corners) = (vec![[0u8; 3]; triangles.len()], Vec::new());
        for node in nodes.iter_mut().filter(|n| n.count > 0) {
            let start = leaf_corners.len();
            for t in node.first as usize..(node.first + node.count) as usize {
                for (k, corner) in triangles[t].iter().enumerate() {
                    let local = match leaf_corners[start..].iter().position(|c| c == corner) {
                        Some(i) => i,
                        None => {
                            leaf_corners.push(*corner);
                            leaf_corners.len() - 1 - start
                        }
                    };
                    corner_of[t][k] = local as u8;
                }
            }
            (node.corners, node.corner_count) = (start as u32, (leaf_corners.len() - start) as u32);
        }
        Ok(Self { triangles, corner_of, leaf_corners, nodes, max_edge })
    }

    /// The triangles after splitting, counter-clockwise seen from outside.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// The longest edge the triangles may have, m.
    pub fn max_edge(&self) -> f32 {
        self.max_edge
    }

    /// The surface's area, m².
    pub fn area(&self) -> f32 {
        self.triangles.iter().map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()).sum()
    }

    /// A sphere holding the surface (its tree's root): centre and radius, m.
    pub fn bound(&self) -> (Vec3, f32) {
        (self.nodes[0].center, self.nodes[0].radius)
    }

    /// Heap bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.triangles.len() * (std::mem::size_of::<[Vec3; 3]>() + 3)
            + self.leaf_corners.len() * std::mem::size_of::<Vec3>()
            + self.nodes.len() * std::mem::size_of::<ShellNode>()
    }

    pub(crate) fn nodes(&self) -> &[ShellNode] {
        &self.nodes
    }

    /// Leaf `node`'s distinct corners, and its triangles' corners as indices into them.
    pub(crate) fn leaf(&self, node: &ShellNode) -> (&[Vec3], &[[u8; 3]]) {
        let corners = &self.leaf_corners[node.corners as usize..(node.corners + node.corner_count) as usize];
        (corners, &self.corner_of[node.first as usize..(node.first + node.count) as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::box_buffers;

    #[test]
    fn a_split_shell_keeps_the_area_and_bounds_every_triangle() {
        let (v, t) = box_buffers(Vec3::new(0.02, 0.01, 0.005));
        let mesh = TriMesh::new(v, t).expect("box");
        let shell = SurfaceShell::new(&mesh, 0.002).expect("shell");
        let area = 2.0 * (0.04 * 0.02 + 0.04 * 0.01 + 0.02 * 0.01);
        assert!((shell.area() / area - 1.0).abs() < 1e-4, "area {} against {area}", shell.area());
        assert!(shell.triangles().len() > 100, "{} triangles", shell.triangles().len());
        for t in shell.triangles() {
            for i in 0..3 {
                assert!(t[i].distance(t[(i + 1) % 3]) <= 0.002 + 1e-7);
            }
        }
        // Every triangle is in exactly one leaf, inside that leaf's and its ancestors' spheres.
        let mut seen = vec![0u32; shell.triangles().len()];
        let mut stack = vec![(0usize, Vec::<usize>::new())];
        while let Some((n, ancestors)) = stack.pop() {
            let node = shell.nodes()[n];
            let mut path = ancestors.clone();
            path.push(n);
            if node.count == 0 {
                stack.push((node.first as usize, path.clone()));
                stack.push((node.first as usize + 1, path));
                continue;
            }
            let (corners, corner_of) = shell.leaf(&node);
            for (i, local) in (node.first..node.first + node.count).zip(corner_of) {
                assert_eq!(local.map(|k| corners[k as usize]), shell.triangles()[i as usize], "a leaf's corners");
                seen[i as usize] += 1;
                for &a in &path {
                    let bound = shell.nodes()[a];
                    for p in shell.triangles()[i as usize] {
                        assert!(p.distance(bound.center) <= bound.radius * (1.0 + 1e-5) + 1e-9);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn a_shell_refuses_a_length_that_is_not_one() {
        let (v, t) = box_buffers(Vec3::splat(0.01));
        let mesh = TriMesh::new(v, t).expect("box");
        for edge in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let error = SurfaceShell::new(&mesh, edge).expect_err("refused");
            assert!(error.to_string().contains("shell edge length"), "{error}");
        }
        let error = SurfaceShell::new(&mesh, 1e-7).expect_err("too many triangles");
        assert!(error.to_string().contains("exceed"), "{error}");
    }
}
