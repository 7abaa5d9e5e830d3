//! Reading and writing `.ist` files.
//!
//! Layout (all little-endian):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `COLLIST\0` |
//! | 8 | 4 | format version (u32, currently 2; version 1 is still read) |
//! | 12 | 4 | header size in bytes (u32, 64) |
//! | 16 | 4 | sphere count S (u32) |
//! | 20 | 4 | node count N (u32) |
//! | 24 | 4 | exact mesh volume (f32) |
//! | 28 | 36 | reserved, zero |
//! | 64 | 20·S | spheres: centre x, y, z, radius, weight (f32) |
//! | 64+20·S | 32·N | nodes: bound centre x, y, z, radius, summed leaf volume, mesh share (f32), first (u32), count with bit 31 set for leaves (u32) |
//! | end−4 | 4 | CRC-32 (IEEE) of every preceding byte |
//!
//! Version 1 had no weight (16-byte spheres) and no mesh share (28-byte nodes): its spheres weigh 1.

use crate::error::IstFileError;
use crate::partitioning::{InnerSphereTree, Node};
use crate::shape::Sphere;
use glam::Vec3;
use std::path::Path;

/// First bytes of every `.ist` file.
pub const MAGIC: [u8; 8] = *b"COLLIST\0";
/// Version written by this library (it also reads version 1).
pub const FORMAT_VERSION: u32 = 2;
/// Size of the fixed header.
pub const HEADER_SIZE: usize = 64;
const SPHERE_SIZE: usize = 20;
const NODE_SIZE: usize = 32;
/// Record sizes (sphere, node) of each version read.
fn record_sizes(version: u32) -> Option<(usize, usize)> {
    match version {
        1 => Some((16, 28)),
        2 => Some((SPHERE_SIZE, NODE_SIZE)),
        _ => None,
    }
}
const LEAF_BIT: u32 = 1 << 31;

impl InnerSphereTree {
    /// Serializes the tree in the `.ist` format.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b =
            Vec::with_capacity(HEADER_SIZE + SPHERE_SIZE * self.spheres.len() + NODE_SIZE * self.nodes.len() + 4);
        b.extend_from_slice(&MAGIC);
        for v in [FORMAT_VERSION, HEADER_SIZE as u32, self.spheres.len() as u32, self.nodes.len() as u32] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.mesh_volume.to_le_bytes());
        b.resize(HEADER_SIZE, 0);
        let f = |b: &mut Vec<u8>, x: f32| b.extend_from_slice(&x.to_le_bytes());
        for (s, w) in self.spheres.iter().zip(&self.weights) {
            for x in [s.center.x, s.center.y, s.center.z, s.radius, *w] {
                f(&mut b, x);
            }
        }
        for n in &self.nodes {
            for x in [n.bound.center.x, n.bound.center.y, n.bound.center.z, n.bound.radius, n.volume, n.mesh_share] {
                f(&mut b, x);
            }
            b.extend_from_slice(&n.first.to_le_bytes());
            b.extend_from_slice(&(n.count | if n.leaf { LEAF_BIT } else { 0 }).to_le_bytes());
        }
        let crc = crc32fast::hash(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    /// Parses an `.ist` image; a truncated, corrupt or foreign input is an error, never a panic.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, IstFileError> {
        let magic_len = bytes.len().min(MAGIC.len());
        if bytes[..magic_len] != MAGIC[..magic_len] {
            return Err(IstFileError::NotAnIstFile);
        }
        if bytes.len() < HEADER_SIZE + 4 {
            return Err(IstFileError::Truncated { expected: HEADER_SIZE + 4, found: bytes.len() });
        }
        let u = |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
        let version = u(8);
        let Some((sphere_size, node_size)) = record_sizes(version) else {
            return Err(IstFileError::UnsupportedVersion { found: version, supported: FORMAT_VERSION });
        };
        if u(12) as usize != HEADER_SIZE {
            return Err(IstFileError::Invalid(format!("header size {} (expected {HEADER_SIZE})", u(12))));
        }
        let (spheres, nodes) = (u(16) as usize, u(20) as usize);
        let expected = HEADER_SIZE + sphere_size * spheres + node_size * nodes + 4;
        if bytes.len() < expected {
            return Err(IstFileError::Truncated { expected, found: bytes.len() });
        }
        if bytes.len() > expected {
            return Err(IstFileError::Invalid(format!("{} bytes after the announced end", bytes.len() - expected)));
        }
        let computed = crc32fast::hash(&bytes[..expected - 4]);
        let found = u(expected - 4);
        if computed != found {
            return Err(IstFileError::ChecksumMismatch { found, computed });
        }
        let f = |at: usize| f32::from_bits(u(at));
        let v3 = |at: usize| Vec3::new(f(at), f(at + 4), f(at + 8));
        let sphere_at = |at: usize| Sphere::new(v3(at), f(at + 12));
        let weighted = version >= 2;
        let mut tree = InnerSphereTree {
            spheres: (0..spheres).map(|i| sphere_at(HEADER_SIZE + sphere_size * i)).collect(),
            weights: (0..spheres).map(|i| if weighted { f(HEADER_SIZE + sphere_size * i + 16) } else { 1.0 }).collect(),
            nodes: (0..nodes)
                .map(|i| {
                    let at = HEADER_SIZE + sphere_size * spheres + node_size * i;
                    let (volume, tail) = (f(at + 16), if weighted { at + 24 } else { at + 20 });
                    let count = u(tail + 4);
                    Node {
                        bound: sphere_at(at),
                        volume,
                        mesh_share: if weighted { f(at + 20) } else { volume },
                        first: u(tail),
                        count: count & !LEAF_BIT,
                        leaf: count & LEAF_BIT != 0,
                    }
                })
                .collect(),
            mesh_volume: f(24),
            blocks: Vec::new(),
            block_of: Vec::new(),
        };
        tree.validate().map_err(IstFileError::Invalid)?;
        tree.rebuild_blocks();
        Ok(tree)
    }

    /// Writes the tree to `path`.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), IstFileError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_bytes()).map_err(|source| IstFileError::Io { path: path.to_owned(), source })
    }

    /// Reads a tree from `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, IstFileError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|source| IstFileError::Io { path: path.to_owned(), source })?;
        Self::from_bytes(&bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::box_buffers;
    use crate::{BuildOptions, TriMesh, build};

    fn sample() -> InnerSphereTree {
        let (v, t) = box_buffers(Vec3::new(1.0, 0.5, 0.25));
        build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(300), &mut |_| {}).expect("builds").0
    }

    #[test]
    fn a_saved_tree_loads_back_identically_and_faster_than_it_builds() {
        let t0 = std::time::Instant::now();
        let tree = sample();
        let build_time = t0.elapsed();
        let path = std::env::temp_dir().join(format!("collette-{}.ist", std::process::id()));
        tree.save(&path).expect("save");
        let t1 = std::time::Instant::now();
        let back = InnerSphereTree::load(&path).expect("load");
        let load_time = t1.elapsed();
        std::fs::remove_file(&path).ok();
        assert_eq!(back, tree);
        assert!(load_time * 10 < build_time, "load {load_time:?} vs build {build_time:?}");
    }

    #[test]
    fn truncated_corrupt_and_foreign_data_are_clear_errors() {
        let bytes = sample().to_bytes();
        for cut in [0, 3, 20, HEADER_SIZE, bytes.len() / 2, bytes.len() - 1] {
            let e = InnerSphereTree::from_bytes(&bytes[..cut]).expect_err("truncated");
            assert!(matches!(e, IstFileError::Truncated { .. }), "cut at {cut}: {e}");
        }
        let mut corrupt = bytes.clone();
        corrupt[HEADER_SIZE + 5] ^= 0x40;
        assert!(matches!(InnerSphereTree::from_bytes(&corrupt), Err(IstFileError::ChecksumMismatch { .. })));
        assert!(matches!(InnerSphereTree::from_bytes(b"# OBJ file\nv 0 0 0\n"), Err(IstFileError::NotAnIstFile)));
        let mut future = bytes.clone();
        future[8] = 9;
        assert!(matches!(InnerSphereTree::from_bytes(&future), Err(IstFileError::UnsupportedVersion { found: 9, .. })));
        let mut longer = bytes;
        longer.push(0);
        assert!(matches!(InnerSphereTree::from_bytes(&longer), Err(IstFileError::Invalid(_))));
    }

    #[test]
    fn a_version_1_file_loads_with_every_sphere_weighing_1() {
        let tree = sample().unweighted();
        let mut v1 = Vec::new();
        v1.extend_from_slice(&tree.to_bytes()[..HEADER_SIZE]);
        v1[8..12].copy_from_slice(&1u32.to_le_bytes());
        for s in tree.spheres() {
            for x in [s.center.x, s.center.y, s.center.z, s.radius] {
                v1.extend_from_slice(&x.to_le_bytes());
            }
        }
        for n in tree.nodes() {
            for x in [n.bound.center.x, n.bound.center.y, n.bound.center.z, n.bound.radius, n.volume] {
                v1.extend_from_slice(&x.to_le_bytes());
            }
            v1.extend_from_slice(&n.first.to_le_bytes());
            v1.extend_from_slice(&(n.count | if n.leaf { LEAF_BIT } else { 0 }).to_le_bytes());
        }
        let crc = crc32fast::hash(&v1);
        v1.extend_from_slice(&crc.to_le_bytes());
        assert_eq!(InnerSphereTree::from_bytes(&v1).expect("version 1 reads"), tree);
    }

    #[test]
    fn a_well_checksummed_but_inconsistent_tree_is_refused() {
        let mut bytes = sample().to_bytes();
        // Point the root past the node array, then fix the checksum so only validation can catch it.
        let root_first = HEADER_SIZE + SPHERE_SIZE * sample().spheres.len() + 24;
        bytes[root_first..root_first + 4].copy_from_slice(&9_999_999u32.to_le_bytes());
        let n = bytes.len() - 4;
        let crc = crc32fast::hash(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        assert!(matches!(InnerSphereTree::from_bytes(&bytes), Err(IstFileError::Invalid(_))));
    }

    #[test]
    fn a_node_no_parent_points_to_is_refused_not_trusted() {
        // An extra inner node nothing reaches, its children far past the node array: before the check
        // it passed validation and deriving the child blocks indexed past the array (a panic).
        let mut tree = sample();
        let stray = Node { first: 9_999_999, count: 4, leaf: false, ..tree.nodes[0] };
        tree.nodes.push(stray);
        let e = InnerSphereTree::from_bytes(&tree.to_bytes()).expect_err("a stray node");
        assert!(e.to_string().contains("not reachable"), "{e}");
    }

    mod fuzz {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]
            #[test]
            fn no_byte_flip_makes_loading_panic(pos in 0usize..4096, value in any::<u8>(), fix_crc in any::<bool>()) {
                static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
                let mut b = BYTES.get_or_init(|| sample().to_bytes()).clone();
                let pos = pos % b.len();
                b[pos] = value;
                if fix_crc {
                    let n = b.len() - 4;
                    let crc = crc32fast::hash(&b[..n]);
                    b[n..].copy_from_slice(&crc.to_le_bytes());
                }
                let _ = InnerSphereTree::from_bytes(&b);
            }
        }
    }
}
