//! Benchmark helpers (being built).
