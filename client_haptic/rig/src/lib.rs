//! haptic_rig (being built).
