//! The desktop mode renders the museum: the real binary under Xvfb on Mesa's CPU Vulkan (lavapipe) joins
//! a running server, takes a screenshot, and the picture is checked — sky above, floor below, enough
//! distinct colours, the walls in between. It also checks the start-up line: no OpenXR runtime here.

use std::io::Read as _;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use heist_server::{ServerOptions, build_server};
use heist_shared::protocol::TICK_HZ;

fn decode(path: &std::path::Path) -> (u32, u32, Vec<[u8; 3]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).expect("screenshot exists")));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    let channels = info.color_type.samples();
    let pixels = buf[..info.buffer_size()].chunks(channels).map(|c| [c[0], c[1], c[2]]).collect();
    (info.width, info.height, pixels)
}

fn is_sky(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    b > 120 && b > r + 30 && g > r
}

#[test]
fn desktop_mode_joins_a_server_and_shows_the_museum() {
    let mut server = build_server(ServerOptions::local_test(10)).expect("server starts");
    let endpoint = server.tokens.as_ref().expect("secure").addr;
    let dir = std::env::temp_dir().join(format!("client_vr_render_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let shot = dir.join("museum.png");
    let _ = std::fs::remove_file(&shot);
    let mut child = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24"])
        .arg(env!("CARGO_BIN_EXE_client_vr"))
        .args(["join", &endpoint.to_string(), "--code", &server.join_code().expect("a secure server").code])
        .args(["--size", "640x480", "--audio", "off", "--shot-after", "150", "--screenshot"])
        .arg(&shot)
        .env_remove("XR_RUNTIME_JSON")
        .env("RUST_LOG", "info,wgpu=error,naga=warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("xvfb-run starts (apt-get install xvfb, see scripts/deps.sh)");
    // Serve in real time while the client runs (bounded).
    let period = Duration::from_secs_f64(1.0 / TICK_HZ);
    let started = Instant::now();
    let status = loop {
        server.app.update();
        if let Some(status) = child.try_wait().expect("child state") {
            break status;
        }
        if started.elapsed() > Duration::from_secs(300) {
            let _ = child.kill();
            panic!("the client did not finish within 300 s");
        }
        std::thread::sleep(period);
    };
    let mut stderr = String::new();
    child.stderr.take().expect("stderr").read_to_string(&mut stderr).expect("stderr reads");
    let mut stdout = String::new();
    child.stdout.take().expect("stdout").read_to_string(&mut stdout).expect("stdout reads");
    let log = format!("{stdout}\n{stderr}");
    assert!(status.success(), "client_vr failed:\n{log}");
    let mode_line = log.lines().find(|l| l.contains("desktop mode:")).unwrap_or_default();
    println!("{mode_line}");
    assert!(mode_line.contains("no OpenXR"), "one clear line says why there is no XR:\n{log}");
    assert!(log.contains("Joined The Night Museum as Vive"), "the client joined:\n{log}");

    let (w, h, px) = decode(&shot);
    assert_eq!((w, h), (640, 480));
    let row = |y: u32| &px[(y * w) as usize..((y + 1) * w) as usize];
    let top: Vec<[u8; 3]> = (0..h / 10).flat_map(|y| row(y).to_vec()).collect();
    let bottom: Vec<[u8; 3]> = (h - h / 10..h).flat_map(|y| row(y).to_vec()).collect();
    let sky_top = top.iter().filter(|p| is_sky(**p)).count() as f32 / top.len() as f32;
    let sky_bottom = bottom.iter().filter(|p| is_sky(**p)).count() as f32 / bottom.len() as f32;
    let mut colours: Vec<[u8; 3]> = px.clone();
    colours.sort_unstable();
    colours.dedup();
    let floorish = bottom.iter().filter(|p| p[0] > p[2] + 15).count() as f32 / bottom.len() as f32;
    println!(
        "screenshot {}: sky in the top tenth {:.0} %, in the bottom tenth {:.0} %, floor-coloured bottom {:.0} %, {} distinct colours",
        shot.display(),
        sky_top * 100.0,
        sky_bottom * 100.0,
        floorish * 100.0,
        colours.len()
    );
    assert!(sky_top > 0.6, "sky above");
    assert!(sky_bottom < 0.05, "no sky below");
    assert!(floorish > 0.6, "floor below");
    assert!(colours.len() > 200, "a scene, not a blank");
    if let Ok(keep) = std::env::var("KEEP_SCREENSHOT") {
        std::fs::copy(&shot, keep).expect("copies the screenshot");
    }
}
