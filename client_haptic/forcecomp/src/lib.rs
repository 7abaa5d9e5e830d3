//! forcecomp (being built).
