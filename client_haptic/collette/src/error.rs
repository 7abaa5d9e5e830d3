//! Errors of the collette library: bad meshes, failed builds, unreadable `.ist` files and bad query settings.

use std::path::PathBuf;

/// Why a triangle mesh was refused.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// The index buffer length is not a multiple of three.
    #[error("the index buffer has {0} entries, not a multiple of 3")]
    RaggedIndices(usize),
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: u32,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The bad vertex index.
        vertex: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle has (nearly) zero area or repeats a vertex.
    #[error("triangle {triangle} (vertices {a}, {b}, {c}) is degenerate")]
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
        /// First vertex.
        a: u32,
        /// Second vertex.
        b: u32,
        /// Third vertex.
        c: u32,
    },
    /// An edge belongs to fewer or more than two triangles, so the mesh is not closed (or not manifold).
    #[error(
        "edge {a}-{b} (first seen in triangle {triangle}) is shared by {count} triangle(s), not 2: the mesh is not closed"
    )]
    OpenEdge {
        /// First vertex of the edge.
        a: u32,
        /// Second vertex of the edge.
        b: u32,
        /// First triangle that uses the edge.
        triangle: usize,
        /// Number of triangles sharing the edge.
        count: u32,
    },
    /// Two triangles traverse an edge in the same direction, so their orientations disagree.
    #[error("edge {a}->{b} is used in the same direction by triangles {first} and {second}: inconsistent orientation")]
    InconsistentOrientation {
        /// First vertex of the directed edge.
        a: u32,
        /// Second vertex of the directed edge.
        b: u32,
        /// First triangle using the directed edge.
        first: usize,
        /// Second triangle using the directed edge.
        second: usize,
    },
    /// The enclosed volume is zero.
    #[error("the mesh encloses no volume")]
    ZeroVolume,
    /// The OBJ file could not be read or parsed.
    #[error("cannot load OBJ file {path}: {message}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// What the OBJ loader said.
        message: String,
    },
}

/// Why building an Inner Sphere Tree failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum BuildError {
    /// The input mesh was refused.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An option is out of range.
    #[error("invalid build option: {0}")]
    InvalidOption(String),
    /// The voxel grid contains no voxel inside the mesh (grid too coarse for the shape).
    #[error("no voxel centre lies inside the mesh; raise the grid resolution")]
    NoInteriorVoxel,
}

/// Why an `.ist` file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum IstFileError {
    /// Reading or writing the file failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The data does not start with the `.ist` magic bytes: it is some other kind of file.
    #[error("not an .ist file (bad magic bytes)")]
    NotAnIstFile,
    /// The file was written by an incompatible version of the format.
    #[error("unsupported .ist format version {found} (this build reads version {supported})")]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// Version this library reads.
        supported: u32,
    },
    /// The file ends before the data its header announces.
    #[error("truncated .ist file: expected {expected} bytes, found {found}")]
    Truncated {
        /// Bytes the header announces.
        expected: usize,
        /// Bytes present.
        found: usize,
    },
    /// The checksum does not match the content.
    #[error("corrupt .ist file: checksum {found:#010x} does not match content {computed:#010x}")]
    ChecksumMismatch {
        /// Checksum stored in the file.
        found: u32,
        /// Checksum of the content read.
        computed: u32,
    },
    /// The content passed the checksum but is not a valid tree.
    #[error("invalid .ist content: {0}")]
    Invalid(String),
}

/// Why a trajectory file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    /// Reading or writing the file failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A line is not a valid sample.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// A neighbour list's skin that is not a length ([`crate::query::CoherentOverlap::new`]).
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq)]
#[error("invalid skin {0}: a neighbour list's skin must be a finite length >= 0")]
pub struct SkinError(pub f32);
