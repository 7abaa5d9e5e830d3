//! The desktop mode renders the museum: the real binary under Xvfb on Mesa's CPU Vulkan (lavapipe) joins
//! a running server, takes a screenshot, and the picture is checked — a museum at night: mostly dark,
//! with what is lit standing out, enough distinct colours, and every guard in view drawn where the server
//! says he is. It also checks the start-up line: no OpenXR runtime here.

use std::io::Read as _;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use client_vr::space;
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
        server.update();
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
    if let Ok(keep) = std::env::var("KEEP_SCREENSHOT") {
        std::fs::copy(&shot, keep).expect("copies the screenshot");
    }
    // A museum at night: mostly dark, yet what is lit (a guard's torch cone, the cases under their
    // spotlights, the exit) stands out; and a scene, not a blank. The HUD's text rows are left out.
    let luma = |p: &[u8; 3]| 0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2]);
    let band: Vec<f32> = (h * 16 / 100..h * 91 / 100)
        .flat_map(|y| px[(y * w) as usize..((y + 1) * w) as usize].iter().map(luma))
        .collect();
    let n = band.len() as f32;
    let mut sorted = band.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    let dark = band.iter().filter(|l| **l < 50.0).count() as f32 / n;
    let lit = band.iter().filter(|l| **l > (5.0 * median).max(60.0)).count() as f32 / n;
    let mut colours: Vec<[u8; 3]> = px.clone();
    colours.sort_unstable();
    colours.dedup();
    println!(
        "screenshot {}: median luma {median:.0}, dark (luma < 50) {:.0} %, lit (> 5 x median) {:.2} %, {} distinct colours",
        shot.display(),
        dark * 100.0,
        lit * 100.0,
        colours.len()
    );
    assert!(dark > 0.6, "night: most of the picture is dark ({:.0} %)", dark * 100.0);
    assert!(median > 4.0, "but not black: the rooms are readable (median luma {median:.1})");
    assert!(lit > 0.001, "the lit things stand out ({:.2} % of the picture over 5 x its median)", lit * 100.0);
    assert!(colours.len() > 200, "a scene, not a blank");

    // Every guard the camera can see is drawn where the server says he is: his alert lamp (green on
    // patrol, glowing, 1.9 m up) lies within 10 px of his server position projected to the screen.
    let level = heist_shared::level::Level::museum();
    let walls = heist_shared::level::WallSet::new(&level);
    // The server's guard lists (Vive's perceived ones and Phantom's whole list), each guard once.
    let guards: Vec<(String, glam::Vec2)> = {
        let world = server.world_mut();
        let mut all: Vec<(String, glam::Vec2)> = Vec::new();
        for list in world.query::<&heist_shared::protocol::Guards>().iter(world) {
            for g in &list.0 {
                if all.iter().all(|(name, _)| *name != g.name) {
                    all.push((g.name.clone(), g.position));
                }
            }
        }
        all
    };
    let eye = space::world(level.vive_spawn, space::EYE_HEIGHT_M);
    // The desktop camera faces east (facing 0) with the default pitch until the mouse moves it.
    let pitch = client_vr::desktop::Look::default().pitch;
    let turn = (space::rotation(0.0) * glam::Quat::from_rotation_x(pitch)).inverse();
    let half = (client_vr::desktop::FOV_DEG.to_radians() * 0.5).tan();
    let is_lamp = |p: [u8; 3]| {
        let [r, g, b] = p.map(i32::from);
        g > 120 && g > r + 40 && g > b + 30
    };
    let mut checked = Vec::new();
    for (name, at) in &guards {
        let local = turn * (space::world(*at, 1.9) - eye);
        let (x, y) = (local.x / (-local.z * half * w as f32 / h as f32), local.y / (-local.z * half));
        if local.z > -0.5 || x.abs() > 0.95 || y.abs() > 0.95 || !walls.line_of_sight(level.vive_spawn, *at) {
            continue; // behind, off screen or behind a wall
        }
        let (sx, sy) = (((x + 1.0) * 0.5 * w as f32) as i64, ((1.0 - y) * 0.5 * h as f32) as i64);
        let near = (-10..=10i64).flat_map(|dy| (-10..=10i64).map(move |dx| (sx + dx, sy + dy)));
        let lamp = near
            .filter(|(x, y)| (0..w as i64).contains(x) && (0..h as i64).contains(y))
            .any(|(x, y)| is_lamp(px[(y as u32 * w + x as u32) as usize]));
        println!("guard {name} at {at} projects to ({sx}, {sy}): lamp {}", if lamp { "seen" } else { "missing" });
        assert!(lamp, "{name}'s lamp is drawn where the server puts him, at ({sx}, {sy})");
        checked.push(name.clone());
    }
    assert!(!checked.is_empty(), "at least one guard is in view from the spawn: {guards:?}");
}
