//! A game written only against bevy_haptics' public API (no haptic_rig or collette import): a tool and
//! three boxes, two spawned in code (a Bevy mesh built on the async pool, a tree added in code) and one
//! from a scene file (its tree an `.ist` file the scene names); the simulated hand presses into each box in turn and
//! the contact observers name the right box, start before end, in that order. Real threads, real time,
//! bounded.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::world_serialization::{DynamicWorldRoot, WorldSerializationPlugin};
use bevy_haptics::prelude::*;

/// Box centres along x, m; each is 2 cm wide with its top at y = 0.01.
const XS: [f32; 3] = [-0.05, 0.0, 0.05];
/// The hand travels at this height between boxes, m.
const ABOVE: f32 = 0.03;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Seen {
    Started(Entity),
    Ended(Entity),
}

#[derive(Resource, Clone, Default)]
struct Log(Arc<Mutex<Vec<Seen>>>);

/// The tools the contact events named.
#[derive(Resource, Clone, Default)]
struct Tools(Arc<Mutex<Vec<Entity>>>);

/// A scene file with one collider: its tree named by path (loaded through the asset server), its
/// material and its place, in the middle of [`XS`].
const SCENE: &str = r#"(
  resources: {},
  entities: {
    4294967290: (
      components: {
        "bevy_haptics::HapticCollider": (tree: Path("box.ist")),
        "bevy_haptics::ForceComponent": (
          stiffness_n_per_m3: 2000000.0,
          damping_ns_per_m: 2.0,
          friction: 0.3,
          ridges: None,
          force_scale: 1.0,
        ),
        "bevy_transform::components::transform::Transform": (
          translation: (0.0, 0.0, 0.0),
          rotation: (0.0, 0.0, 0.0, 1.0),
          scale: (1.0, 1.0, 1.0),
        ),
      },
    ),
  },
)"#;

/// A 2 cm box's tree.
fn box_tree() -> SphereTree {
    SphereTree::from_mesh(&Cuboid::new(0.02, 0.02, 0.02).into(), 1.0, 300).expect("a box packs")
}

#[test]
fn contacts_with_three_colliders_start_and_end_in_the_order_the_hand_presses_them() {
    let dir = std::env::temp_dir().join(format!("bevy-haptics-api-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temp dir");
    // A box's tree saved as an `.ist` file, as the `collette` tool writes them, and a scene file that
    // places a collider with that tree and a soft material over the middle.
    box_tree().save(dir.join("box.ist")).expect("saves");
    std::fs::write(dir.join("box.scn.ron"), SCENE).expect("writes the scene");

    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin { file_path: dir.to_string_lossy().into_owned(), ..default() },
        HapticsPlugins,
        WorldSerializationPlugin,
    ))
    .init_asset::<Mesh>()
    // The scene's Bevy type (Bevy without its default `reflect_auto_register` registers none by itself).
    .register_type::<Transform>()
    .insert_resource(HapticDevice::simulated("phantom desktop", Vec3::new(XS[0], ABOVE, 0.0)));
    let log = Log::default();
    app.insert_resource(log.clone());
    let tools = Tools::default();
    app.insert_resource(tools.clone());
    app.add_observer(|c: On<ContactStarted>, log: Res<Log>, tools: Res<Tools>| {
        log.0.lock().unwrap().push(Seen::Started(c.object));
        tools.0.lock().unwrap().push(c.tool);
    });
    app.add_observer(|c: On<ContactEnded>, log: Res<Log>, tools: Res<Tools>| {
        log.0.lock().unwrap().push(Seen::Ended(c.object));
        tools.0.lock().unwrap().push(c.tool);
    });

    let world = app.world_mut();
    let tool = world.spawn(HapticTool::ball(0.003)).id();
    let mesh = world.resource_mut::<Assets<Mesh>>().add(Cuboid::new(0.02, 0.02, 0.02));
    let from_mesh =
        world.spawn((Mesh3d(mesh), SphereTreeFromMesh { spheres: 300 }, Transform::from_xyz(XS[0], 0.0, 0.0))).id();
    let scene = world.resource::<AssetServer>().load("box.scn.ron");
    world.spawn(DynamicWorldRoot(scene));
    let added = world.resource_mut::<Assets<SphereTree>>().add(box_tree());
    let from_code =
        world.spawn((HapticCollider::new(added), ForceComponent::default(), Transform::from_xyz(XS[2], 0.0, 0.0))).id();
    app.finish();
    app.cleanup();

    let step = |app: &mut App| {
        app.update();
        std::thread::sleep(Duration::from_millis(5));
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    // Every collider reaches the collision thread (trees loaded and built).
    let ready = |app: &mut App| {
        let world = app.world_mut();
        let mut q = world.query::<&HapticCollider>();
        let trees = world.resource::<Assets<SphereTree>>();
        q.iter(world).filter(|c| trees.get(&c.tree).is_some()).count() == 3
    };
    while !ready(&mut app) {
        assert!(Instant::now() < deadline, "the three trees were not ready in time");
        step(&mut app);
    }
    // The scene's collider: the one neither spawned in code.
    let mut colliders = app.world_mut().query_filtered::<Entity, With<HapticCollider>>();
    let from_file =
        colliders.iter(app.world()).find(|e| ![from_mesh, from_code].contains(e)).expect("the scene file's collider");
    let soft = app.world().get::<ForceComponent>(from_file).expect("the scene gave it a material");
    assert_eq!(soft.stiffness_n_per_m3, 2e6, "the scene's material, not the default");
    assert_eq!(
        app.world().get::<GlobalTransform>(from_file).expect("placed").translation(),
        Vec3::new(XS[1], 0.0, 0.0)
    );
    assert!(matches!(app.world().resource::<HapticStatus>(), HapticStatus::Running { .. }));

    for (i, x) in XS.into_iter().enumerate() {
        let press = |to: Vec3, seconds: f32, app: &mut App| {
            app.world_mut().resource_mut::<SimulatedHand>().move_to(to, seconds);
            let until = Instant::now() + Duration::from_secs_f32(seconds + 0.4);
            while Instant::now() < until {
                step(app);
            }
        };
        press(Vec3::new(x, ABOVE, 0.0), 0.4, &mut app);
        press(Vec3::new(x, 0.0, 0.0), 0.4, &mut app);
        press(Vec3::new(x, ABOVE, 0.0), 0.4, &mut app);
        assert!(Instant::now() < deadline, "box {i} took too long");
    }
    let seen = log.0.lock().unwrap().clone();
    let expected = [from_mesh, from_file, from_code].into_iter().flat_map(|e| [Seen::Started(e), Seen::Ended(e)]);
    assert_eq!(seen, expected.collect::<Vec<_>>(), "mesh {from_mesh}, file {from_file}, code {from_code}");
    let named = tools.0.lock().unwrap().clone();
    assert!(named.len() == 6 && named.iter().all(|&t| t == tool), "every event names the tool {tool}: {named:?}");
    // The tool's Transform follows the device: after the last press it hovers above the third box.
    let mut q = app.world_mut().query_filtered::<&Transform, With<HapticTool>>();
    let at = q.iter(app.world()).next().expect("the tool").translation;
    assert!((at - Vec3::new(XS[2], ABOVE, 0.0)).length() < 0.01, "the tool is at {at}");
    let stats = *app.world().resource::<HapticStats>();
    assert_eq!(stats.contacts_started, 3);
    assert!(stats.max_force_n > 0.1 && stats.max_force_n <= 7.9 + 1e-3, "{stats:?}");
    assert!(!stats.non_finite);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_device_that_cannot_be_opened_is_reported_and_the_app_runs_on_without_haptics() {
    let device = HapticDevice::named("trace:/nonexistent/hand.csv").expect("a device name");
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), HapticsPlugins)).insert_resource(device);
    app.world_mut().spawn(HapticTool::ball(0.003));
    app.finish();
    app.cleanup();
    for _ in 0..3 {
        app.update();
    }
    match app.world().resource::<HapticStatus>() {
        HapticStatus::Failed(why) => {
            assert!(why.contains("/nonexistent/hand.csv") && !why.contains('\n'), "{why}");
        }
        other => panic!("expected a failure, got {other:?}"),
    }
    assert!(app.world().get_resource::<SimulatedHand>().is_none());
    let err = HapticDevice::named("inverse3").expect_err("not a device name");
    assert!(err.contains("sim, trace:FILE, hid[:PATH], falcon[:FIRMWARE] or haply[:URL]"), "{err}");
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum PairSeen {
    Started(Entity, Entity, f32),
    Ended(Entity, Entity),
}

#[derive(Resource, Clone, Default)]
struct PairLog(Arc<Mutex<Vec<PairSeen>>>);

/// Two boxes and a watcher between them (no tool near them): apart nothing is heard; moved half into
/// each other by their `Transform`s, the watcher hears them meet (with some overlap); moved apart, part;
/// together again, then one despawned: part once more.
#[test]
fn a_watcher_between_two_colliders_hears_them_meet_and_part_where_the_game_moves_them() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), HapticsPlugins))
        .init_asset::<Mesh>()
        .insert_resource(HapticDevice::simulated("phantom desktop", Vec3::new(0.0, 0.2, 0.0)));
    let log = PairLog::default();
    app.insert_resource(log.clone());
    let world = app.world_mut();
    let tree = world.resource_mut::<Assets<SphereTree>>().add(box_tree());
    let a = world.spawn((HapticCollider::new(tree.clone()), Transform::from_xyz(-0.05, 0.0, 0.0))).id();
    let b = world.spawn((HapticCollider::new(tree), Transform::from_xyz(0.05, 0.0, 0.0))).id();
    let watcher = world
        .spawn(CollisionWatcher::new(a, b))
        .observe(|c: On<PairContactStarted>, log: Res<PairLog>| {
            log.0.lock().unwrap().push(PairSeen::Started(c.a, c.b, c.volume_m3));
        })
        .observe(|c: On<PairContactEnded>, log: Res<PairLog>| {
            log.0.lock().unwrap().push(PairSeen::Ended(c.a, c.b));
        })
        .id();
    app.finish();
    app.cleanup();
    let deadline = Instant::now() + Duration::from_secs(60);
    let run_until = |app: &mut App, n: usize| {
        while log.0.lock().unwrap().len() < n {
            assert!(Instant::now() < deadline, "heard only {:?}", log.0.lock().unwrap());
            app.update();
            std::thread::sleep(Duration::from_millis(5));
        }
    };
    let place_b = |app: &mut App, x: f32| {
        app.world_mut().get_mut::<Transform>(b).expect("b").translation.x = x;
    };
    // Apart for half a second: nothing.
    let quiet = Instant::now() + Duration::from_millis(500);
    while Instant::now() < quiet {
        app.update();
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(log.0.lock().unwrap().is_empty(), "apart: {:?}", log.0.lock().unwrap());
    // Half of b's 2 cm inside a: an overlap of 1 x 2 x 2 cm, 4e-6 m³.
    place_b(&mut app, -0.04);
    run_until(&mut app, 1);
    place_b(&mut app, 0.05);
    run_until(&mut app, 2);
    place_b(&mut app, -0.04);
    run_until(&mut app, 3);
    app.world_mut().despawn(a);
    run_until(&mut app, 4);
    let seen = log.0.lock().unwrap().clone();
    // A Transform's move reaches the threads as a pose track: b slides from where it was to where it is
    // over 20 ms, so they meet on the way and the event may come while b is only partly in (the overlap
    // when the game thread heard of it). Some overlap, never more than the whole 4e-6 m³ (with the sphere
    // trees' slack); the rig's own test checks the settled overlap of a pose set at once.
    let PairSeen::Started(_, _, volume) = seen[0] else { panic!("{seen:?}") };
    assert!(volume > 0.0 && volume < 8e-6, "overlap {volume} m³");
    let expected = [PairSeen::Started(a, b, volume), PairSeen::Ended(a, b)];
    assert_eq!(seen[..2], expected, "watcher {watcher}: a {a}, b {b}");
    assert!(matches!(seen[2], PairSeen::Started(x, y, _) if (x, y) == (a, b)), "{seen:?}");
    assert_eq!(seen[3], PairSeen::Ended(a, b), "a despawned collider ends its watcher's contact");
}

/// A game's own rigid body (no physics engine): a velocity, a table's friction, and the pushes.
#[derive(Component, Default)]
struct Body {
    velocity: Vec3,
    pushes: u32,
}

#[test]
fn a_pushable_box_is_handed_the_pushes_that_move_it_the_way_the_hand_goes() {
    const MASS_KG: f32 = 0.1;
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), HapticsPlugins))
        .init_asset::<Mesh>()
        .insert_resource(HapticDevice::simulated("touch", Vec3::new(-0.04, 0.0, 0.0)));
    let world = app.world_mut();
    world.spawn(HapticTool::ball(0.005));
    let tree = world.resource_mut::<Assets<SphereTree>>().add(box_tree());
    // The game applies each push to its body (an observer on the box) and moves it (a system).
    let boxed = world
        .spawn((HapticCollider::new(tree), HapticPushable::new(MASS_KG), Body::default(), Transform::default()))
        .observe(|push: On<ToolPushed>, mut bodies: Query<&mut Body>| {
            let mut body = bodies.get_mut(push.object).expect("the box");
            body.velocity += push.impulse_ns / MASS_KG;
            body.pushes += 1;
        })
        .id();
    app.add_systems(Update, |time: Res<Time>, mut bodies: Query<(&mut Body, &mut Transform)>| {
        let dt = time.delta_secs();
        for (mut body, mut t) in &mut bodies {
            let rub = 0.3 * 9.81 * dt;
            let v = Vec3::new(body.velocity.x, 0.0, body.velocity.z);
            body.velocity = if v.length() <= rub { Vec3::ZERO } else { v - v.normalize() * rub };
            t.translation += body.velocity * dt;
        }
    });
    app.finish();
    app.cleanup();
    // The hand (its ball 3 cm left of the box's 2 cm face) goes 7 cm along +x over 1.4 s.
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut moved = false;
    while Instant::now() < deadline {
        app.update();
        std::thread::sleep(Duration::from_millis(5));
        let world = app.world_mut();
        if let Some(mut hand) = world.get_resource_mut::<SimulatedHand>()
            && !moved
        {
            hand.move_to(Vec3::new(0.03, 0.0, 0.0), 1.4);
            moved = true;
        }
        let x = world.get::<Transform>(boxed).expect("box").translation.x;
        if x > 0.03 {
            break;
        }
    }
    let world = app.world();
    let (t, body) = (world.get::<Transform>(boxed).expect("box"), world.get::<Body>(boxed).expect("body"));
    assert!(t.translation.x > 0.03, "pushed along +x: {:?} after {} pushes", t.translation, body.pushes);
    assert!(t.translation.z.abs() < 0.01, "straight: {:?}", t.translation);
}
