//! heist_server (being built).
