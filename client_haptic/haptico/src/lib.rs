//! haptico (being built).
