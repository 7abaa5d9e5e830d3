//! heist_client (being built).
