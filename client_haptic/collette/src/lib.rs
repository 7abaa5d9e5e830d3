//! collette (being built).
