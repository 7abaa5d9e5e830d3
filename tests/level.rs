//! Level files: the shipped one loads; a bad one gives an error naming the file, the place and the problem.

#![allow(clippy::unwrap_used)] // helpers outside the #[test] fns unwrap too: a panic fails the test

use heist_shared::level::{Level, LevelError};

fn write(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("heist-level-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn the_shipped_museum_loads_from_disk() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/levels/museum.ron");
    let level = Level::load(path).unwrap();
    assert_eq!(level, Level::museum());
}

#[test]
fn a_missing_file_names_the_file() {
    let e = Level::load("/nonexistent/museum.ron").unwrap_err();
    assert!(matches!(e, LevelError::Io { .. }));
    assert!(e.to_string().starts_with("/nonexistent/museum.ron: cannot read"), "{e}");
}

#[test]
fn a_door_on_no_shared_wall_is_reported_with_its_place() {
    let text = include_str!("../assets/levels/museum.ron").replace("at: (24.0, 16.0)", "at: (20.0, 16.0)");
    let path = write("door.ron", &text);
    let e = Level::load(&path).unwrap_err().to_string();
    assert!(e.contains("door.ron") && e.contains("doors[5]") && e.contains("not on a wall shared"), "{e}");
}

#[test]
fn truncated_files_and_garbage_give_line_and_column() {
    let text = include_str!("../assets/levels/museum.ron");
    let path = write("cut.ron", &text[..text.len() / 2]);
    let e = Level::load(&path).unwrap_err();
    assert!(matches!(e, LevelError::Syntax { line, .. } if line > 1), "{e}");
    let path = write("garbage.ron", "\u{0}\u{1}\u{2} not a level");
    assert!(matches!(Level::load(&path).unwrap_err(), LevelError::Syntax { .. }));
}
