//! heist_bots (being built).
