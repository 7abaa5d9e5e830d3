//! What a frame of the Vive client's desktop view costs: the museum at night mid-heist, drawn by the
//! client's own world, palette and HUD plugins through Bevy's renderer on whatever Vulkan is here
//! (lavapipe, Mesa's CPU rasteriser, on the CI machines), at 1280×720 by default.
//!
//! The scene: every room, all 12 cases lit with their copies (9 copies of three looks and 3 props), the
//! three guards walking their rounds with their torches (Bruno at a run: a chase), the west gallery's
//! three cases shattering one after another (frames 61, 161, 261), a prop thrown from Vive's hand
//! down the gallery (frame 55), the HUD as mid-heist; the camera
//! stands in the west gallery looking east along both galleries (three cases, Bruno and his torch in
//! view). There is no server: the replicated views are spawned and the
//! guards' tracks fed at the server's rate, as the network would.
//!
//! It prints, over the measured frames (after a warm-up): the wall time per frame (p50/p95/max), the CPU
//! time per main-world schedule and per client system set (`Update` and `PostUpdate` run single-threaded
//! here so their sets do not overlap), the render world's time per render set, and the draw calls per
//! render phase and the meshes visible to any view (the camera's or a torch's shadow map). Run it with
//! `cargo bench -p client_vr --bench frame_time -- [--frames N] [--warmup N] [--size WxH] [--no-shadows]
//! [--screenshot PATH]` (the last measured frame, to see what was measured);
//! without a display it runs itself again under `xvfb-run`.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::app::{AppExit, MainScheduleOrder, RunFixedMainLoop};
use bevy::camera::visibility::ViewVisibility;
use bevy::core_pipeline::core_3d::{AlphaMask3d, Opaque3d, Transparent3d};
use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
use bevy::pbr::Shadow;
use bevy::prelude::*;
use bevy::render::render_phase::{BinnedPhaseItem, SortedPhaseItem, ViewBinnedRenderPhases, ViewSortedRenderPhases};
use bevy::render::{Render, RenderApp, RenderPlugin, RenderSystems};
use bevy::window::{PresentMode, WindowResolution};
use client_vr::client::ViveState;
use client_vr::interp::{Snapshot, Track};
use client_vr::space;
use client_vr::world::WorldSystems;
use glam::Vec2;
use heist_shared::artifact::{ArtifactKind, look};
use heist_shared::level::{Level, WallSet};
use heist_shared::protocol::{
    CaseId, CaseView, GuardAlert, GuardId, GuardView, ItemId, ItemKind, ItemPlace, ItemView, Phase, SessionView,
    TICK_HZ,
};

/// What the bench measures, from its command line.
#[derive(Clone, Copy, Debug)]
struct Options {
    frames: u32,
    warmup: u32,
    size: (u32, u32),
    shadows: bool,
}

/// Where to save the last measured frame (`--screenshot PATH`), so the scene measured can be seen.
#[derive(Resource, Clone, Debug, Default)]
struct ShotPath(Option<std::path::PathBuf>);

fn options() -> Result<(Options, ShotPath), String> {
    let mut o = Options::default();
    let mut shot = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--frames" => o.frames = value("--frames")?.parse().map_err(|e| format!("--frames: {e}"))?,
            "--warmup" => o.warmup = value("--warmup")?.parse().map_err(|e| format!("--warmup: {e}"))?,
            "--size" => {
                let v = value("--size")?;
                let (w, h) = v.split_once('x').ok_or(format!("--size {v}: expected WxH"))?;
                o.size =
                    (w.parse().map_err(|e| format!("--size: {e}"))?, h.parse().map_err(|e| format!("--size: {e}"))?);
            }
            "--no-shadows" => o.shadows = false,
            "--screenshot" => shot = Some(std::path::PathBuf::from(value("--screenshot")?)),
            "--bench" => {} // what `cargo bench` passes
            other => {
                return Err(format!(
                    "unknown argument `{other}` (--frames N, --warmup N, --size WxH, --no-shadows, --screenshot PATH)"
                ));
            }
        }
    }
    if o.frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    Ok((o, ShotPath(shot)))
}

fn main() {
    let (options, shot) = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("frame_time: {e}");
            std::process::exit(2);
        }
    };
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        // No display: the same bench again under a virtual X server of the window's size.
        let screen = format!("-screen 0 {}x{}x24", options.size.0, options.size.1);
        let me = std::env::current_exe().expect("the bench's own path");
        let status = std::process::Command::new("xvfb-run")
            .args(["-a", "-s", &screen])
            .arg(me)
            .args(std::env::args().skip(1))
            .status()
            .unwrap_or_else(|e| {
                eprintln!("frame_time: no display and xvfb-run would not start ({e}); see scripts/deps.sh");
                std::process::exit(2)
            });
        std::process::exit(status.code().unwrap_or(1));
    }
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: Some(Window {
                    title: "Phantom Heist — frame time".into(),
                    resolution: WindowResolution::new(options.size.0, options.size.1),
                    // Frames as fast as they can be made: the bench measures the work, not the display.
                    present_mode: PresentMode::AutoNoVsync,
                    ..default()
                }),
                ..default()
            })
            .set(RenderPlugin { synchronous_pipeline_compilation: true, ..default() }),
    )
    .insert_resource(ViveState {
        level: Some(Level::museum()),
        walls: Some(WallSet::new(&Level::museum())),
        phase: Phase::Heist,
        time_left_s: 421.0,
        alarm: 1,
        ..default()
    })
    .add_plugins((client_vr::world::WorldPlugin, client_vr::hud::HudPlugin { wrist: false }))
    // The scene runs on a fixed 30 Hz clock whatever the frame costs, so every run draws the same
    // frames (guards, shards) and a screenshot frame is the same picture; the wall time is measured apart.
    .insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(1.0 / SCENE_HZ)))
    .insert_resource(Bench { options, ..default() })
    .insert_resource(shot)
    .add_systems(Startup, stage)
    .add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin)
    .add_systems(Update, (drive, count_in_view, finish).chain().before(WorldSystems));
    if !options.shadows {
        app.add_systems(PostUpdate, no_shadows);
    }
    timings(&mut app);
    match app.run() {
        AppExit::Success => {}
        AppExit::Error(code) => std::process::exit(i32::from(code.get())),
    }
}

/// The bench's state: its options, frames so far and everything measured.
#[derive(Resource, Default)]
struct Bench {
    options: Options,
    frame: u32,
    frame_starts: Vec<Instant>,
    in_view: Vec<usize>,
    shown: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self { frames: 300, warmup: 60, size: (1280, 720), shadows: true }
    }
}

/// Where the camera stands: the west gallery's west end, eyes at standing height, looking east.
const CAMERA_AT: Vec2 = Vec2::new(11.0, 4.0);
/// The scene clock's rate: each frame moves the scene on by 1/30 s.
const SCENE_HZ: f64 = 30.0;
/// Bruno's start along his round, seconds of walking: on frame 68 he runs west at the camera in the
/// middle of the west gallery, torch ahead, just after the first case shattered, the thrown prop in
/// the air.
const BRUNO_AHEAD_S: f32 = 11.6;

/// The prop Vive throws, on this frame, to there.
const THROWN: ItemId = ItemId(100);
const THROW_FRAME: u32 = 55;
const THROWN_TO: Vec2 = Vec2::new(17.0, 3.0);

/// The west gallery's cases in the order they shatter (west_3 on the left of the view first, then
/// west_1 near on the right, then west_2 far on the right), by index in the level.
const SHATTER_ORDER: [usize; 3] = [2, 0, 1];
/// The frame the first shatters at, and the frames between two.
const SHATTER_FIRST_FRAME: u32 = 61;
const SHATTER_EVERY_FRAMES: u32 = 100;

#[derive(Component)]
struct Walker {
    route: Vec<Vec2>,
    speed: f32,
    ahead_s: f32,
}

fn stage(mut commands: Commands, mut state: ResMut<ViveState>) {
    // The HUD as mid-heist: the session, and the guards' radio on the feed.
    commands.spawn(SessionView {
        phase: Phase::Heist,
        time_left_s: 421.0,
        alarm: 1,
        targets: vec![(ArtifactKind::Crown, false), (ArtifactKind::Amphora, true), (ArtifactKind::Idol, false)],
        present: (true, true),
        ..default()
    });
    state.say(0.0, "Phantom's verdict: Secured".into());
    state.say(0.0, "RADIO Bruno: intruder seen in the west_gallery".into());
    // A prop in Vive's hand, thrown down the gallery on frame THROW_FRAME.
    state.carrying = vec![THROWN];
    commands.spawn(ItemView { id: THROWN, kind: ItemKind::Prop, place: ItemPlace::Carried });
    let camera = space::world(CAMERA_AT, space::EYE_HEIGHT_M);
    commands.insert_resource(client_vr::world::Hands { main: camera + Vec3::new(0.4, -0.35, 0.3), other: camera });
    let Some(level) = state.level.clone() else { return };
    commands.spawn((
        Camera3d::default(),
        Projection::Perspective(PerspectiveProjection { fov: client_vr::desktop::FOV_DEG.to_radians(), ..default() }),
        Transform::from_translation(space::world(CAMERA_AT, space::EYE_HEIGHT_M))
            .with_rotation(space::rotation(0.0) * Quat::from_rotation_x(client_vr::desktop::Look::default().pitch)),
    ));
    let kinds = [ArtifactKind::Crown, ArtifactKind::Amphora, ArtifactKind::Idol];
    for (i, case) in level.cases.iter().enumerate() {
        let id = u16::try_from(i).unwrap_or(u16::MAX);
        commands.spawn(CaseView { id: CaseId(id), position: case.at, broken: false });
        let kind = if i < 9 {
            let k = kinds[i % 3];
            ItemKind::Copy { artifact: k, look: look(k) }
        } else {
            ItemKind::Prop
        };
        commands.spawn(ItemView { id: ItemId(id), kind, place: ItemPlace::InCase(CaseId(id)) });
    }
    for (i, g) in level.guards.iter().enumerate() {
        let chasing = i == 0;
        commands.spawn((
            GuardView {
                id: GuardId(u16::try_from(i).unwrap_or(u16::MAX)),
                name: g.name.clone(),
                position: g.route[0],
                facing: 0.0,
                alert: if chasing { GuardAlert::Chasing } else { GuardAlert::Patrolling },
            },
            Walker {
                route: g.route.clone(),
                speed: if chasing { 2.6 } else { 1.1 },
                ahead_s: if chasing { BRUNO_AHEAD_S } else { 0.0 },
            },
            Track::default(),
        ));
    }
}

/// Where a guard walking `route` back and forth at `speed` is after `t` seconds, and which way he faces.
fn along(route: &[Vec2], speed: f32, t: f32) -> (Vec2, f32) {
    let legs: Vec<(Vec2, Vec2)> =
        route.windows(2).map(|w| (w[0], w[1])).chain(route.windows(2).rev().map(|w| (w[1], w[0]))).collect();
    let total: f32 = legs.iter().map(|(a, b)| a.distance(*b)).sum();
    if total <= 0.0 {
        return (route[0], 0.0);
    }
    let mut d = (speed * t) % total;
    for (a, b) in &legs {
        let len = a.distance(*b);
        if d <= len {
            let dir = (*b - *a) / len;
            return (*a + dir * d, dir.y.atan2(dir.x));
        }
        d -= len;
    }
    (route[0], 0.0)
}

/// Feeds the guards' tracks at the server's rate and shatters a case every few seconds, as the network would.
fn drive(
    mut bench: ResMut<Bench>,
    time: Res<Time>,
    mut guards: Query<(&Walker, &mut GuardView, &mut Track)>,
    mut cases: Query<&mut CaseView>,
    mut items: Query<&mut ItemView>,
    mut state: ResMut<ViveState>,
    mut last_tick: Local<f64>,
) {
    let now = time.elapsed_secs_f64();
    bench.frame_starts.push(Instant::now());
    bench.frame += 1;
    if now - *last_tick >= 1.0 / TICK_HZ - 1e-6 {
        *last_tick = now;
        for (walker, mut view, mut track) in &mut guards {
            let (at, facing) = along(&walker.route, walker.speed, now as f32 + walker.ahead_s);
            view.position = at;
            view.facing = facing;
            track.push(Snapshot { t: now, position: space::world(at, 0.0), rotation: space::rotation(facing) });
        }
    }
    if bench.frame == THROW_FRAME
        && let Some(mut thrown) = items.iter_mut().find(|i| i.id == THROWN)
    {
        thrown.place = ItemPlace::Floor(THROWN_TO);
        state.carrying.clear();
    }
    // The west gallery's three cases shatter one after another (then stay broken), inside the measured
    // frames with the defaults; a screenshot one frame after one of them shows the shards in the air.
    for (n, &case) in SHATTER_ORDER.iter().enumerate() {
        if bench.frame == SHATTER_FIRST_FRAME + SHATTER_EVERY_FRAMES * n as u32
            && let Some(mut c) = cases.iter_mut().find(|c| usize::from(c.id.0) == case)
        {
            c.broken = true;
        }
    }
}

/// Turns every torch's shadows off (`--no-shadows`: what the shadow maps cost).
fn no_shadows(mut lights: Query<&mut SpotLight>) {
    for mut l in &mut lights {
        l.shadow_maps_enabled = false;
    }
}

/// Meshes the camera sees this frame (after last frame's culling).
fn count_in_view(mut bench: ResMut<Bench>, meshes: Query<&ViewVisibility, With<Mesh3d>>) {
    let n = meshes.iter().filter(|v| v.get()).count();
    bench.in_view.push(n);
}

fn finish(
    mut commands: Commands,
    shot: Res<ShotPath>,
    mut bench: ResMut<Bench>,
    mut exit: MessageWriter<AppExit>,
    stamps: Res<Stamps>,
    render: Res<RenderStamps>,
    store: Res<bevy::diagnostic::DiagnosticsStore>,
) {
    let Options { frames, warmup, size, .. } = bench.options;
    if let Some(path) = &shot.0
        && bench.frame == warmup + frames
    {
        use bevy::render::view::screenshot::{Screenshot, save_to_disk};
        commands.spawn(Screenshot::primary_window()).observe(save_to_disk(path.clone()));
    }
    // With a screenshot to save, a few more frames let it reach the disk.
    let extra = if shot.0.is_some() { 8 } else { 2 };
    if bench.shown || bench.frame < warmup + frames + extra {
        return;
    }
    bench.shown = true;
    let main = stamps.0.lock().map(|s| s.clone()).unwrap_or_default();
    let render = render.0.lock().map(|s| s.clone()).unwrap_or_default();
    report(&bench, size, warmup, frames, &main, &render);
    // Bevy's own per-pass figures (timestamp queries on the device: lavapipe's are CPU time too).
    println!("  render passes, median of the last frames Bevy keeps (ms, CPU encode / device):");
    let mut passes: Vec<(String, f64, f64)> = Vec::new();
    for d in store.iter() {
        let path = d.path().as_str();
        let (pass, field) = match path.rsplit_once('/') {
            Some(split) => split,
            None => continue,
        };
        let mut values: Vec<f64> = d.values().copied().collect();
        values.sort_by(f64::total_cmp);
        let median = percentile(&values, 0.5);
        let i = passes.iter().position(|(p, ..)| p == pass).unwrap_or_else(|| {
            passes.push((pass.to_string(), f64::NAN, f64::NAN));
            passes.len() - 1
        });
        match field {
            "elapsed_cpu" => passes[i].1 = median,
            "elapsed_gpu" => passes[i].2 = median,
            _ => {}
        }
    }
    passes.retain(|(_, cpu, gpu)| !cpu.is_nan() || !gpu.is_nan());
    passes.sort_by(|a, b| b.2.total_cmp(&a.2));
    for (pass, cpu, gpu) in passes {
        println!("      {pass:<44} {cpu:7.3} / {gpu:8.3}");
    }
    exit.write(AppExit::Success);
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn summary(mut xs: Vec<f64>) -> (f64, f64, f64) {
    xs.sort_by(f64::total_cmp);
    (percentile(&xs, 0.5), percentile(&xs, 0.95), xs.last().copied().unwrap_or(f64::NAN))
}

fn report(bench: &Bench, size: (u32, u32), warmup: u32, frames: u32, main: &Timings, render: &Timings) {
    let measured = |f: u32| f > warmup && f <= warmup + frames;
    let walls: Vec<f64> = bench
        .frame_starts
        .windows(2)
        .enumerate()
        .filter(|(i, _)| measured(*i as u32 + 1))
        .map(|(_, w)| (w[1] - w[0]).as_secs_f64() * 1e3)
        .collect();
    let (p50, p95, max) = summary(walls);
    let adapter = format!(", on {}", render.adapter);
    let shadows = if bench.options.shadows { "torch shadows on" } else { "torch shadows off" };
    println!("frame_time: {}x{}, {frames} frames after {warmup} warm-up, {shadows}{adapter}", size.0, size.1);
    println!(
        "  wall time per frame      p50 {p50:7.2} ms   p95 {p95:7.2} ms   max {max:7.2} ms   ({:.1} fps at p50)",
        1e3 / p50
    );
    println!("  CPU per frame, ms (p50 / p95):");
    for (label, times) in [("main world", main), ("render world", render)] {
        println!("    {label}");
        for (span, per_frame) in &times.spans {
            let xs: Vec<f64> =
                per_frame.iter().filter(|(f, _)| measured(*f)).map(|(_, d)| d.as_secs_f64() * 1e3).collect();
            if xs.is_empty() {
                continue;
            }
            let (p50, p95, _) = summary(xs);
            println!("      {span:<44} {p50:7.3} / {p95:7.3}");
        }
    }
    println!("  draw calls per frame (p50 / max), by render phase and view kind:");
    for (phase, per_frame) in &render.counts {
        let xs: Vec<f64> = per_frame.iter().filter(|(f, _)| measured(*f)).map(|(_, n)| *n as f64).collect();
        if xs.is_empty() {
            continue;
        }
        let (p50, _, max) = summary(xs);
        println!("      {phase:<44} {p50:7.0} / {max:5.0}");
    }
    let seen: Vec<f64> =
        bench.in_view.iter().enumerate().filter(|(i, _)| measured(*i as u32 + 1)).map(|(_, n)| *n as f64).collect();
    let (p50, _, max) = summary(seen);
    println!("  meshes visible to any view (camera or shadow map)   p50 {p50:.0}   max {max:.0}");
}

/// Spans timed per frame: name → (frame, duration); counts per frame: name → (frame, count); each in
/// the order first seen (the order they run in).
#[derive(Clone, Debug, Default)]
struct Timings {
    spans: Vec<(String, Vec<(u32, Duration)>)>,
    counts: Vec<(String, Vec<(u32, usize)>)>,
    adapter: String,
}

/// The entry for `name` in an ordered list, added at the end the first time.
fn entry<'a, T>(list: &'a mut Vec<(String, Vec<T>)>, name: &str) -> &'a mut Vec<T> {
    let i = list.iter().position(|(n, _)| n == name).unwrap_or_else(|| {
        list.push((name.to_string(), Vec::new()));
        list.len() - 1
    });
    &mut list[i].1
}

/// The main world's timings, shared with the stamping systems.
#[derive(Resource, Clone, Default)]
struct Stamps(Arc<Mutex<Timings>>);

/// The render world's timings (written on the render thread, read by the main world at the end).
#[derive(Resource, Clone, Default)]
struct RenderStamps(Arc<Mutex<Timings>>);

/// The frame the main world is on (copied into the render world at extraction).
#[derive(Resource, Clone, Copy, Default)]
struct FrameNo(u32);

/// When the previous stamp of this world was taken in this frame.
#[derive(Resource, Default)]
struct Clock(Option<Instant>);

macro_rules! stamp_schedule {
    ($name:ident) => {
        #[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
        struct $name;
    };
}
stamp_schedule!(AfterFirst);
stamp_schedule!(AfterPreUpdate);
stamp_schedule!(AfterFixed);
stamp_schedule!(AfterUpdate);
stamp_schedule!(AfterPostUpdate);
stamp_schedule!(AfterLast);

/// A system that closes the span `name`: from the previous stamp to now.
fn close(name: &'static str) -> impl FnMut(Res<Stamps>, ResMut<Clock>, Res<Bench>) {
    move |stamps: Res<Stamps>, mut clock: ResMut<Clock>, bench: Res<Bench>| {
        let now = Instant::now();
        if let (Some(from), Ok(mut t)) = (clock.0, stamps.0.lock()) {
            entry(&mut t.spans, name).push((bench.frame, now - from));
        }
        clock.0 = Some(now);
    }
}

fn render_close(name: &'static str) -> impl FnMut(Res<RenderStamps>, ResMut<Clock>, Res<FrameNo>) {
    move |stamps: Res<RenderStamps>, mut clock: ResMut<Clock>, frame: Res<FrameNo>| {
        let now = Instant::now();
        if let (Some(from), Ok(mut t)) = (clock.0, stamps.0.lock()) {
            entry(&mut t.spans, name).push((frame.0, now - from));
        }
        clock.0 = Some(now);
    }
}

fn render_open(mut clock: ResMut<Clock>) {
    clock.0 = Some(Instant::now());
}

fn timings(app: &mut App) {
    let stamps = Stamps::default();
    let render = RenderStamps::default();
    app.insert_resource(stamps.clone()).insert_resource(render.clone()).init_resource::<Clock>();
    // Main world: a stamp between the main schedules (each stamp is a one-system schedule of its own).
    {
        let mut order = app.world_mut().resource_mut::<MainScheduleOrder>();
        order.insert_after(First, AfterFirst);
        order.insert_after(PreUpdate, AfterPreUpdate);
        order.insert_after(RunFixedMainLoop, AfterFixed);
        order.insert_after(Update, AfterUpdate);
        order.insert_after(PostUpdate, AfterPostUpdate);
        order.insert_after(Last, AfterLast);
    }
    // First is timed from the previous frame's end: that span holds winit's events, the wait for the
    // render world to finish the last frame (pipelined rendering) and the extraction.
    app.add_systems(AfterFirst, close("main: wait for the render world, extract, First"))
        .add_systems(AfterPreUpdate, close("main: PreUpdate"))
        .add_systems(AfterFixed, close("main: RunFixedMainLoop"))
        .add_systems(AfterPostUpdate, close("main: PostUpdate (transforms, visibility, culling)"))
        .add_systems(AfterLast, close("main: Last"));
    // Update: single-threaded, stamped around the world's systems and the HUD.
    app.edit_schedule(Update, |s| {
        s.set_executor(SingleThreadedExecutor::new());
    });
    app.edit_schedule(PostUpdate, |s| {
        s.set_executor(SingleThreadedExecutor::new());
    });
    app.add_systems(Update, close("main: Update before the world (bench's feed)").before(WorldSystems).after(finish))
        .add_systems(Update, close("main: Update, WorldSystems (dress, move, shatter)").after(WorldSystems))
        .add_systems(AfterUpdate, close("main: Update after the world (HUD, rest)"));

    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        eprintln!("frame_time: no render app (no GPU adapter?)");
        std::process::exit(2);
    };
    render_app
        .insert_resource(render)
        .init_resource::<Clock>()
        .init_resource::<FrameNo>()
        .add_systems(
            bevy::render::ExtractSchedule,
            |mut frame: ResMut<FrameNo>, main: bevy::render::Extract<Res<Bench>>| {
                frame.0 = main.frame;
            },
        )
        .add_systems(Render, render_open.before(RenderSystems::ExtractCommands))
        .add_systems(
            Render,
            render_close("render: commands, assets, meshes")
                .after(RenderSystems::PrepareMeshes)
                .before(RenderSystems::CreateViews),
        )
        .add_systems(
            Render,
            render_close("render: views, specialize").after(RenderSystems::PrepareViews).before(RenderSystems::Queue),
        )
        .add_systems(Render, render_close("render: queue").after(RenderSystems::Queue).before(RenderSystems::PhaseSort))
        .add_systems(
            Render,
            render_close("render: sort").after(RenderSystems::PhaseSort).before(RenderSystems::Prepare),
        )
        .add_systems(
            Render,
            (render_close("render: prepare (batching, buffers, bind groups)"), count_draws)
                .chain()
                .after(RenderSystems::Prepare)
                .before(RenderSystems::Render),
        )
        .add_systems(
            Render,
            render_close("render: render (encode, submit, present)")
                .after(RenderSystems::Render)
                .before(RenderSystems::Cleanup),
        )
        .add_systems(
            Render,
            render_close("render: cleanup").after(RenderSystems::Cleanup).before(RenderSystems::PostCleanup),
        );
}

/// API draw calls a binned phase issues (as its `render` does: one per multidraw batch set, per
/// batchable bin, per unbatchable entity and per non-mesh item).
fn binned_draws<B: BinnedPhaseItem>(phases: &ViewBinnedRenderPhases<B>) -> usize {
    phases
        .values()
        .map(|p| {
            p.multidrawable_meshes.len()
                + p.batchable_meshes.len()
                + p.unbatchable_meshes.values().map(|u| u.entities.len()).sum::<usize>()
                + p.non_mesh_items.values().map(|n| n.entities.len()).sum::<usize>()
        })
        .sum()
}

/// Draw calls a sorted phase issues (one per batch, as its `render_range` walks them).
fn sorted_draws<S: SortedPhaseItem>(phases: &ViewSortedRenderPhases<S>) -> usize {
    phases
        .values()
        .map(|p| {
            let items: Vec<&S> = p.items.values().collect();
            let (mut i, mut n) = (0, 0);
            while i < items.len() {
                let len = items[i].batch_range().len();
                n += usize::from(len > 0);
                i += len.max(1);
            }
            n
        })
        .sum()
}

fn count_draws(
    stamps: Res<RenderStamps>,
    frame: Res<FrameNo>,
    opaque: Option<Res<ViewBinnedRenderPhases<Opaque3d>>>,
    mask: Option<Res<ViewBinnedRenderPhases<AlphaMask3d>>>,
    transparent: Option<Res<ViewSortedRenderPhases<Transparent3d>>>,
    shadow: Option<Res<ViewBinnedRenderPhases<Shadow>>>,
    adapter: Res<bevy::render::renderer::RenderAdapterInfo>,
) {
    let counts = [
        ("Opaque3d (camera)", opaque.map_or(0, |p| binned_draws(&p))),
        ("AlphaMask3d (camera)", mask.map_or(0, |p| binned_draws(&p))),
        ("Transparent3d (camera: glass)", transparent.map_or(0, |p| sorted_draws(&p))),
        ("Shadow (all shadow-casting torches' views)", shadow.map_or(0, |p| binned_draws(&p))),
    ];
    if let Ok(mut t) = stamps.0.lock() {
        if t.adapter.is_empty() {
            t.adapter = format!("{} ({:?}, {})", adapter.name, adapter.backend, adapter.driver_info);
        }
        let total: usize = counts.iter().map(|(_, n)| n).sum();
        for (name, n) in counts {
            entry(&mut t.counts, name).push((frame.0, n));
        }
        entry(&mut t.counts, "total (3-D phases; the HUD's text not counted)").push((frame.0, total));
    }
}
