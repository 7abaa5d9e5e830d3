//! The `.ist` file format: save a built tree once, load it in milliseconds.
//!
//! You need this module (or the `save`/`load` methods it adds to [`crate::InnerSphereTree`]) to ship
//! prebuilt trees with your assets instead of packing at start-up.

mod ist_file;

pub use ist_file::{FORMAT_VERSION, HEADER_SIZE, MAGIC};
