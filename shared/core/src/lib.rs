//! heist_shared (being built).
