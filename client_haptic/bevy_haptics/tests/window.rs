//! touch_bunny's window renders under Xvfb on Mesa's CPU Vulkan (lavapipe): the stroke's script presses
//! the tool onto the bunny's back, the example saves a screenshot and quits; the picture must show the
//! lit bunny and the red rod of the force on the device (docs/img/bevy_touch_bunny.png is this picture).

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod support;

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
fn touch_bunny_shows_the_lit_bunny_and_the_force_under_xvfb_on_lavapipe() {
    let example = support::example("touch_bunny");
    let shot = std::env::temp_dir().join(format!("bevy-haptics-touch-bunny-{}.png", std::process::id()));
    let _ = std::fs::remove_file(&shot);
    let mut child = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x720x24"])
        .arg(example)
        .arg("--screenshot")
        .arg(&shot)
        .env("WGPU_BACKEND", "vulkan")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("xvfb-run runs (scripts/deps.sh installs xvfb and mesa-vulkan-drivers)");
    let deadline = Instant::now() + Duration::from_secs(300);
    let status = loop {
        if let Some(status) = child.try_wait().expect("waits") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("touch_bunny did not quit within 5 minutes");
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    assert!(status.success(), "touch_bunny exited with {status}");
    let (w, h, px) = decode(&shot);
    assert_eq!((w, h), (1280, 720));
    let bg = px[0];
    assert!(bg.iter().all(|&c| c < 40), "background {bg:?}");
    // The bunny is a warm white, shaded: many bright pixels in many tones.
    let bunny: Vec<&[u8; 3]> = px.iter().filter(|p| p[0] > 90 && p[0] >= p[2] && p[0].abs_diff(p[1]) < 40).collect();
    assert!(bunny.len() > 20_000, "{} bunny-coloured pixels", bunny.len());
    let mut tones: Vec<u8> = bunny.iter().map(|p| p[0] >> 2).collect();
    tones.sort_unstable();
    tones.dedup();
    assert!(tones.len() > 15, "only {} tones: the bunny is not lit", tones.len());
    // The force rod: the tool presses on the bunny, so the device pushes back.
    let red = px.iter().filter(|p| p[0] > 150 && p[1] < 90 && p[2] < 90).count();
    assert!(red > 50, "{red} red pixels: no force shown");
    let _ = std::fs::remove_file(&shot);
}
