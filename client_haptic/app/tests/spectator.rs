//! The spectator window renders under Xvfb on Mesa's CPU Vulkan (lavapipe): the real binary practises
//! on an idol with the touch bot, saves a screenshot and quits; the picture must show the scene.
#![cfg(feature = "spectator")]

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Decodes an 8-bit RGB(A) PNG into (width, height, RGB pixels).
fn decode(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).expect("the screenshot exists")));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    let step = info.color_type.samples();
    let px = buf[..info.buffer_size()].chunks(step).map(|c| [c[0], c[1], c[2]]).collect();
    (info.width, info.height, px)
}

#[test]
fn the_spectator_window_shows_the_copy_under_xvfb_on_lavapipe() {
    let shot = std::env::temp_dir().join(format!("phantom-spectator-{}.png", std::process::id()));
    let _ = std::fs::remove_file(&shot);
    let mut child = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_client_haptic"))
        .args([
            "practice",
            "--kind",
            "idol",
            "--seed",
            "3",
            "--bot",
            "--audio",
            "memory",
            "--shot-after",
            "150",
            "--screenshot",
        ])
        .arg(&shot)
        .env("WGPU_BACKEND", "vulkan")
        .stdout(Stdio::null())
        .spawn()
        .expect("xvfb-run runs (scripts/deps.sh installs xvfb and mesa-vulkan-drivers)");
    let deadline = Instant::now() + Duration::from_secs(600);
    let status = loop {
        if let Some(status) = child.try_wait().expect("waits") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the spectator did not quit within 10 minutes");
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    assert!(status.success(), "client_haptic exited with {status}");
    let (w, h, px) = decode(&shot);
    assert_eq!((w, h), (640, 480));
    // The background (top-left corner) is the dark clear colour; the scene fills the middle.
    let bg = px[0];
    assert!(bg.iter().all(|&c| c < 40), "background {bg:?}");
    let differs = |p: &[u8; 3]| p.iter().zip(bg).any(|(a, b)| a.abs_diff(b) > 12);
    let lit = px.iter().filter(|p| differs(p)).count();
    assert!(lit > px.len() / 10, "only {lit} of {} pixels show something", px.len());
    let mut colours: Vec<[u8; 3]> = px.iter().map(|p| [p[0] >> 3, p[1] >> 3, p[2] >> 3]).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 60, "only {} distinct colours: the scene is not shaded", colours.len());
    // The idol's grey-green (sRGB 120, 128, 110) is lit somewhere in the middle of the picture.
    let idol = px.iter().filter(|p| p[1] >= p[2] && p[1] + 10 >= p[0] && p[1] > 60 && p[0].abs_diff(p[2]) < 60).count();
    assert!(idol > 2000, "{idol} idol-coloured pixels");
    let _ = std::fs::remove_file(&shot);
}
