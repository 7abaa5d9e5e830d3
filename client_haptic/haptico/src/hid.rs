//! HID devices (being built).
