//! heist_tests (being built).
