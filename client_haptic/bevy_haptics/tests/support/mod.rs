//! What the tests that run the examples share.

use std::path::PathBuf;

/// The example's binary, built by `cargo test` beside the test's (target/<profile>/examples/).
pub fn example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    let profile = exe.parent().and_then(|deps| deps.parent()).expect("target/<profile>/deps/<test>");
    let path = profile.join("examples").join(name);
    assert!(path.exists(), "{} is not built: `cargo test -p bevy_haptics` builds the examples", path.display());
    path
}
