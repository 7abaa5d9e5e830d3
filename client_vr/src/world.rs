//! The museum Vive sees: its rooms (built by [`crate::museum`] from the level file), with the replicated
//! cases, items, guards and the Phantom's tool dressed as meshes and moved every frame.
//!
//! Display cases are pedestals
//! with a glass box that shatters into falling shards; every copy of one artifact is drawn from the same
//! [`ArtifactLook`](heist_shared::artifact::ArtifactLook) — the client cannot tell the real one; guards
//! carry a lamp over the head in their alert colour; Phantom sits at the workbench with his tool; a
//! thrown item flies from the hand to where the server landed it along a ballistic arc ([`Flight`]).

use bevy::prelude::*;
use glam::{Vec2, Vec3};
use heist_shared::protocol::{CaseView, GuardAlert, GuardView, ItemKind, ItemPlace, ItemView, PhantomTool};

use crate::client::{ViveState, ViveSystems};
use crate::figure::{self, Gait, Limb, Neck};
use crate::flight::Flight;
use crate::interp::{DELAY_S, Track};
use crate::palette::{METER_WIDTH_M, PEDESTAL_M, Palette};
use crate::space::{self, BENCH_TOP_M};

/// The night sky's colour.
pub const SKY: Color = Color::srgb(0.01, 0.015, 0.04);
/// Light of a display case's spotlight, lumens (as a point light: about 2,000 lux on the artifact).
pub const CASE_LIGHT_LM: f32 = 100_000.0;
/// Light of a guard's torch, lumens (as a point light: about 3,000 lux 6 m ahead).
pub const TORCH_LM: f32 = 1_500_000.0;
/// Torches that cast shadows at once (shadow maps are the expensive part of a light).
pub const MAX_SHADOWED_TORCHES: u32 = 4;

/// Where carried items are held, world positions (the desktop camera's or the controllers').
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct Hands {
    /// The main hand.
    pub main: Vec3,
    /// The other hand.
    pub other: Vec3,
}

/// The world's systems (in `ViveSystems::Present`).
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct WorldSystems;

/// Builds and moves the museum.
pub struct WorldPlugin;

impl Plugin for WorldPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(ClearColor(SKY))
            .init_resource::<Hands>()
            .init_resource::<Palette>()
            .insert_resource(GlobalAmbientLight { color: Color::srgb(0.55, 0.62, 0.9), brightness: 60.0, ..default() })
            .add_systems(
                Update,
                (
                    crate::museum::build_museum,
                    dress_cases,
                    dress_items,
                    dress_guards,
                    dress_tool,
                    shatter,
                    move_items,
                    move_guards,
                    move_tool,
                    fall,
                )
                    .chain()
                    .in_set(ViveSystems::Present)
                    .in_set(WorldSystems),
            );
    }
}

#[derive(Component)]
struct Glass;

#[derive(Component)]
struct Shard {
    velocity: Vec3,
    spin: Vec3,
}

#[derive(Component)]
struct AlertLamp;

/// The awareness meter over a guard's head: a bar that fills as he grows alert.
#[derive(Component)]
pub struct AwarenessMeter;

/// How full a guard's awareness meter is, as stealth games show it: empty on patrol, a third when
/// something caught his eye, two thirds while he investigates or searches, full in a chase; a guard
/// going back to his round keeps a third (he is still wary).
pub fn awareness(alert: GuardAlert) -> f32 {
    match alert {
        GuardAlert::Patrolling => 0.0,
        GuardAlert::Suspicious | GuardAlert::Returning => 1.0 / 3.0,
        GuardAlert::Investigating | GuardAlert::Searching => 2.0 / 3.0,
        GuardAlert::Chasing => 1.0,
    }
}

#[derive(Component)]
struct Dressed;

fn dress_cases(mut commands: Commands, cases: Query<(Entity, &CaseView), Without<Dressed>>, palette: Res<Palette>) {
    for (e, case) in &cases {
        commands
            .entity(e)
            .insert((Dressed, Transform::from_translation(space::world(case.position, 0.0)), Visibility::default()))
            .with_children(|c| {
                c.spawn((
                    Mesh3d(palette.pedestal.0.clone()),
                    MeshMaterial3d(palette.pedestal.1.clone()),
                    Transform::from_xyz(0.0, PEDESTAL_M * 0.5, 0.0),
                ));
                // A warm spotlight from above onto the artifact (no shadows: there are a dozen).
                c.spawn((
                    SpotLight {
                        color: Color::srgb(1.0, 0.9, 0.75),
                        intensity: CASE_LIGHT_LM,
                        range: 4.0,
                        outer_angle: 0.45,
                        inner_angle: 0.3,
                        shadow_maps_enabled: false,
                        ..default()
                    },
                    Transform::from_xyz(0.0, PEDESTAL_M + 1.8, 0.0)
                        .looking_at(Vec3::new(0.0, PEDESTAL_M, 0.0), Vec3::Z),
                ));
                if !case.broken {
                    c.spawn((
                        Glass,
                        Mesh3d(palette.glass.0.clone()),
                        MeshMaterial3d(palette.glass.1.clone()),
                        Transform::from_xyz(0.0, PEDESTAL_M + 0.225, 0.0),
                    ));
                }
            });
    }
}

/// A case turned broken: its glass becomes shards that fly and fall.
fn shatter(
    mut commands: Commands,
    cases: Query<(&CaseView, &Children), Changed<CaseView>>,
    glass: Query<(Entity, &GlobalTransform), With<Glass>>,
    palette: Res<Palette>,
) {
    for (case, children) in &cases {
        if !case.broken {
            continue;
        }
        for child in children.iter() {
            let Ok((e, at)) = glass.get(child) else { continue };
            let centre = at.translation();
            commands.entity(e).despawn();
            for i in 0..24u32 {
                // A fixed spray pattern: the look, not physics, is the point.
                let a = i as f32 * 2.399_963;
                let r = 0.5 + (i % 5) as f32 * 0.25;
                let velocity = Vec3::new(a.cos() * r, 1.0 + (i % 3) as f32 * 0.6, a.sin() * r);
                commands.spawn((
                    Shard { velocity, spin: Vec3::new(3.0 + i as f32 * 0.3, 5.0, 2.0) },
                    Mesh3d(palette.shard.clone()),
                    MeshMaterial3d(palette.glass.1.clone()),
                    Transform::from_translation(centre + Vec3::new(a.cos(), 0.0, a.sin()) * 0.2),
                ));
            }
        }
    }
}

fn fall(mut shards: Query<(&mut Shard, &mut Transform)>, time: Res<Time>) {
    let dt = time.delta_secs();
    for (mut s, mut t) in &mut shards {
        if t.translation.y <= 0.003 {
            continue;
        }
        s.velocity.y -= 9.81 * dt;
        t.translation += s.velocity * dt;
        let spin = s.spin * dt;
        t.rotate(Quat::from_euler(EulerRot::XYZ, spin.x, spin.y, spin.z));
        if t.translation.y <= 0.003 {
            t.translation.y = 0.003;
            t.rotation = Quat::from_rotation_y(t.rotation.to_euler(EulerRot::YXZ).0);
        }
    }
}

fn dress_items(
    mut commands: Commands,
    items: Query<(Entity, &ItemView), Without<Dressed>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut palette: ResMut<Palette>,
) {
    for (e, item) in &items {
        let (mesh, material) = match &item.kind {
            ItemKind::Copy { look, .. } => palette.look(look, &mut meshes, &mut materials),
            ItemKind::Prop => palette.prop.clone(),
        };
        commands.entity(e).insert((
            Dressed,
            Drawn { place: item.place, flight: None },
            Mesh3d(mesh),
            MeshMaterial3d(material),
            Transform::default(),
            Visibility::Hidden,
        ));
    }
}

/// Where an item was when last drawn, and the arc it is drawn along while a throw is in the air.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Drawn {
    /// The server's place for it at the last frame.
    pub place: ItemPlace,
    /// Its throw, until it lands.
    pub flight: Option<Flight>,
}

fn move_items(
    mut items: Query<(&ItemView, &mut Drawn, &mut Transform, &mut Visibility), Without<CaseView>>,
    cases: Query<&CaseView>,
    state: Res<ViveState>,
    hands: Res<Hands>,
    time: Res<Time>,
) {
    let bench = state.level.as_ref().map_or(Vec2::ZERO, |l| l.workbench);
    let now = time.elapsed_secs_f64();
    for (item, mut drawn, mut t, mut vis) in &mut items {
        let at = match item.place {
            ItemPlace::InCase(c) => {
                cases.iter().find(|cv| cv.id == c).map(|cv| space::world(cv.position, PEDESTAL_M + 0.1))
            }
            ItemPlace::Floor(p) => Some(space::world(p, 0.08)),
            ItemPlace::Carried => {
                let slot = state.carrying.iter().position(|i| *i == item.id).unwrap_or(0);
                Some(if slot == 0 { hands.main } else { hands.other })
            }
            ItemPlace::Workbench => Some(space::world(bench, BENCH_TOP_M + 0.08)),
            ItemPlace::Secured | ItemPlace::Discarded => None,
        };
        // Carried one frame, on the floor the next: thrown. It flies from where it was drawn (the hand).
        if let (ItemPlace::Carried, ItemPlace::Floor(_), Some(landing)) = (drawn.place, item.place, at) {
            drawn.flight = Some(Flight::between(t.translation, landing, now));
        }
        if !matches!(item.place, ItemPlace::Floor(_)) {
            drawn.flight = None; // picked up again (or gone) before it landed
        }
        drawn.place = item.place;
        let flying = drawn.flight.and_then(|f| f.at(now));
        if flying.is_none() {
            drawn.flight = None;
        }
        match flying.or(at) {
            Some(p) => {
                t.translation = p;
                *vis = Visibility::Inherited;
            }
            None => *vis = Visibility::Hidden,
        }
    }
}

/// A guard's torch: where its light falls is where he looks.
#[derive(Component)]
pub struct Torch;

fn dress_guards(
    mut commands: Commands,
    guards: Query<(Entity, &GuardView), Without<Dressed>>,
    palette: Res<Palette>,
    mut shadowed: Local<u32>,
) {
    let mut torch_on = Vec::new();
    for (e, g) in &guards {
        let shadows = *shadowed < MAX_SHADOWED_TORCHES;
        *shadowed += u32::from(shadows);
        let lamp = palette.alert(g.alert);
        commands
            .entity(e)
            .insert((
                Dressed,
                Gait::default(),
                Transform::from_translation(space::world(g.position, 0.0)),
                Visibility::default(),
            ))
            .with_children(|c| {
                let neck = figure::spawn(
                    c,
                    &figure::Parts {
                        torso: (&palette.guard_body.0, &palette.guard_body.1),
                        leg: &palette.guard_leg,
                        arm: &palette.guard_arm,
                        head: (&palette.guard_head.0, &palette.guard_nose, &palette.guard_head.1),
                    },
                );
                torch_on.push((neck, shadows));
                c.spawn((
                    AlertLamp,
                    Mesh3d(palette.lamp.clone()),
                    MeshMaterial3d(lamp.clone()),
                    Transform::from_xyz(0.0, 1.9, 0.0),
                ));
                c.spawn((
                    AwarenessMeter,
                    Mesh3d(palette.meter.clone()),
                    MeshMaterial3d(lamp),
                    meter_transform(g.alert),
                    if awareness(g.alert) > 0.0 { Visibility::Inherited } else { Visibility::Hidden },
                ));
            });
        // The torch in his right hand at the shoulder, turning with his head: its cone is where he looks.
        for (neck, shadows) in torch_on.drain(..) {
            commands.entity(neck).with_child((
                Torch,
                SpotLight {
                    color: Color::srgb(1.0, 0.96, 0.85),
                    intensity: TORCH_LM,
                    range: 14.0,
                    outer_angle: 0.4,
                    inner_angle: 0.25,
                    shadow_maps_enabled: shadows,
                    ..default()
                },
                Transform::from_xyz(0.25, -0.15, -0.2).with_rotation(Quat::from_rotation_x(-0.12)),
            ));
        }
    }
}

/// The meter's place over the head, its bar scaled to the awareness (growing from the left end).
fn meter_transform(alert: GuardAlert) -> Transform {
    let fill = awareness(alert).max(1e-3);
    Transform::from_xyz(-METER_WIDTH_M * 0.5 * (1.0 - fill), 2.1, 0.0).with_scale(Vec3::new(fill, 1.0, 1.0))
}

#[allow(clippy::type_complexity)]
fn move_guards(
    mut guards: Query<(&GuardView, &Track, &mut Gait, &mut Transform, &Children), Without<AwarenessMeter>>,
    mut meters: Query<(&mut Transform, &mut Visibility), (With<AwarenessMeter>, Without<Limb>, Without<Neck>)>,
    mut lamps: Query<&mut MeshMaterial3d<StandardMaterial>, Or<(With<AlertLamp>, With<AwarenessMeter>)>>,
    mut limbs: Query<(&Limb, &mut Transform), (Without<Neck>, Without<Gait>)>,
    mut necks: Query<&mut Transform, (With<Neck>, Without<Limb>, Without<Gait>)>,
    palette: Res<Palette>,
    time: Res<Time>,
) {
    let t = time.elapsed_secs_f64() - DELAY_S;
    for (g, track, mut gait, mut transform, children) in &mut guards {
        // Drawn where the track says he was; his body turns the way he walks, his head the way he looks.
        let look = match track.sample(t) {
            Some((p, r)) => {
                transform.translation = p;
                let look = space::facing(r);
                gait.step(space::floor(p), look, time.delta_secs());
                look
            }
            None => gait.body,
        };
        figure::pose(&gait, look, &mut transform, children, &mut limbs, &mut necks);
        let glow = palette.alert(g.alert);
        for child in children.iter() {
            if let Ok((mut t, mut vis)) = meters.get_mut(child) {
                t.set_if_neq(meter_transform(g.alert));
                vis.set_if_neq(if awareness(g.alert) > 0.0 { Visibility::Inherited } else { Visibility::Hidden });
            }
            if let Ok(mut m) = lamps.get_mut(child) {
                m.set_if_neq(MeshMaterial3d(glow.clone()));
            }
        }
    }
}

fn dress_tool(
    mut commands: Commands,
    tool: Query<Entity, (With<PhantomTool>, Without<Dressed>)>,
    palette: Res<Palette>,
) {
    for e in &tool {
        commands.entity(e).insert((
            Dressed,
            Mesh3d(palette.tool.0.clone()),
            MeshMaterial3d(palette.tool.1.clone()),
            Transform::default(),
            Visibility::default(),
        ));
    }
}

fn move_tool(mut tool: Query<(&Track, &mut Transform), With<PhantomTool>>, time: Res<Time>) {
    let t = time.elapsed_secs_f64() - DELAY_S;
    for (track, mut transform) in &mut tool {
        if let Some((p, r)) = track.sample(t) {
            transform.translation = p;
            transform.rotation = r;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::ItemId;
    use std::time::Duration;

    /// An app with a clock, the asset stores and the palette: what dressing and moving need.
    fn dressing_app() -> App {
        let mut app = App::new();
        app.insert_resource(Time::<()>::default())
            .init_resource::<Assets<Mesh>>()
            .init_resource::<Assets<StandardMaterial>>()
            .init_resource::<Assets<Image>>()
            .init_resource::<Palette>();
        app
    }

    #[test]
    fn the_awareness_meter_over_a_guard_fills_as_he_grows_alert_and_hides_on_patrol() {
        let mut app = dressing_app();
        app.add_systems(Update, move_guards);
        let view = |alert| GuardView {
            id: heist_shared::protocol::GuardId(1),
            name: "Bruno".into(),
            position: Vec2::ZERO,
            facing: 0.0,
            alert,
        };
        let guard = app
            .world_mut()
            .spawn((view(GuardAlert::Patrolling), Track::default(), Gait::default(), Transform::default()))
            .id();
        let meter = app
            .world_mut()
            .spawn((
                AwarenessMeter,
                MeshMaterial3d::<StandardMaterial>::default(),
                Transform::default(),
                Visibility::Inherited,
                ChildOf(guard),
            ))
            .id();
        let mut seen = Vec::new();
        for alert in [
            GuardAlert::Patrolling,
            GuardAlert::Suspicious,
            GuardAlert::Investigating,
            GuardAlert::Chasing,
            GuardAlert::Searching,
            GuardAlert::Returning,
            GuardAlert::Patrolling,
        ] {
            *app.world_mut().get_mut::<GuardView>(guard).expect("guard") = view(alert);
            app.update();
            let t = *app.world().get::<Transform>(meter).expect("meter");
            let shown = *app.world().get::<Visibility>(meter).expect("meter") != Visibility::Hidden;
            // The bar grows from its left end, which stays put.
            assert!((t.translation.x - t.scale.x * METER_WIDTH_M * 0.5 + METER_WIDTH_M * 0.5).abs() < 1e-4);
            let glow = app.world().get::<MeshMaterial3d<StandardMaterial>>(meter).map(|m| m.0.clone());
            assert_eq!(
                glow,
                Some(app.world().resource::<Palette>().alert(alert)),
                "the meter glows in the alert's colour"
            );
            seen.push((shown, (t.scale.x * 3.0).round() as u8));
        }
        assert_eq!(
            seen,
            vec![(false, 0), (true, 1), (true, 2), (true, 3), (true, 2), (true, 1), (false, 0)],
            "hidden on patrol; a third when suspicious, two thirds investigating or searching, full chasing"
        );
    }

    #[test]
    fn a_guard_walking_one_way_and_looking_another_is_drawn_so_with_his_torch_where_he_looks() {
        use crate::interp::Snapshot;
        use heist_shared::protocol::GuardId;
        let mut app = dressing_app();
        app.add_systems(Update, (dress_guards, move_guards).chain());
        // The server's guard walks east at a patrol's 1.1 m/s, looking north (his track, as replicated).
        let look = std::f32::consts::FRAC_PI_2;
        let snapshot = |t: f64| Snapshot {
            t,
            position: space::world(Vec2::new(1.1 * t as f32, 0.0), 0.0),
            rotation: space::rotation(look),
        };
        let view = GuardView {
            id: GuardId(1),
            name: "Bruno".into(),
            position: Vec2::ZERO,
            facing: look,
            alert: GuardAlert::Patrolling,
        };
        let guard = app.world_mut().spawn((view, Track::default())).id();
        let mut legs = Vec::new();
        let mut sent = 0u32;
        for _ in 0..180 {
            app.world_mut().resource_mut::<Time>().advance_by(Duration::from_millis(16));
            let now = app.world().resource::<Time>().elapsed_secs_f64();
            while f64::from(sent) / 30.0 <= now {
                app.world_mut().get_mut::<Track>(guard).expect("track").push(snapshot(f64::from(sent) / 30.0));
                sent += 1;
            }
            app.update();
            let world = app.world_mut();
            let mut q = world.query::<(&Limb, &Transform, &ChildOf)>();
            let swing: Vec<f32> = q
                .iter(world)
                .filter(|(l, _, parent)| !l.arm && parent.parent() == guard)
                .map(|(l, t, _)| l.side * t.rotation.to_axis_angle().1 * t.rotation.x.signum())
                .collect();
            legs.push(swing);
        }
        let world = app.world_mut();
        let root = *world.get::<Transform>(guard).expect("placed");
        assert!(
            (space::facing(root.rotation)).abs() < 0.01,
            "his body faces east, where he walks: {} at {}",
            space::facing(root.rotation),
            root.translation
        );
        assert!(
            (root.translation.x - 1.1 * (180.0 * 0.016 - DELAY_S as f32)).abs() < 0.1,
            "drawn where the track says"
        );
        let (neck, torch) = {
            let mut q = world.query_filtered::<(&Transform, &Children), With<Neck>>();
            let (neck, children) = q.iter(world).next().expect("a neck");
            let torch =
                children.iter().find_map(|c| world.get::<SpotLight>(c).map(|_| c)).expect("the torch on the neck");
            (*neck, *world.get::<Transform>(torch).expect("torch"))
        };
        let beam = root.rotation * neck.rotation * torch.rotation * Vec3::NEG_Z;
        let beam_facing = space::floor(beam).to_angle();
        assert!(
            (beam_facing - (space::facing(root.rotation) + figure::MAX_HEAD_TURN)).abs() < 0.01,
            "the head and torch turn as far to his left (north) as a head turns: beam at {beam_facing}"
        );
        // Both legs swing, against each other, as wide as a patrol's walk.
        let settled = &legs[90..];
        assert!(settled.iter().all(|s| s.len() == 2), "two legs");
        let peak = settled.iter().map(|s| s[0].abs()).fold(0.0, f32::max);
        assert!((peak - figure::swing(1.1)).abs() < 0.05, "swing {peak}");
        assert!(settled.iter().all(|s| (s[0] - s[1]).abs() < 1e-3), "mirrored legs: {:?}", &settled[..4]);
    }

    #[test]
    fn every_case_guard_and_copy_is_dressed_from_the_shared_palette() {
        use heist_shared::artifact::{ArtifactKind, look};
        use heist_shared::protocol::{CaseId, GuardId, ItemId};
        let mut app = dressing_app();
        app.add_systems(Update, (dress_cases, dress_items, dress_guards));
        let counts = |app: &App| {
            (app.world().resource::<Assets<Mesh>>().len(), app.world().resource::<Assets<StandardMaterial>>().len())
        };
        let before = counts(&app);
        for i in 0..12u16 {
            app.world_mut().spawn(CaseView { id: CaseId(i), position: Vec2::new(f32::from(i), 0.0), broken: false });
            let kind = if i % 2 == 0 { ArtifactKind::Crown } else { ArtifactKind::Idol };
            let item = ItemKind::Copy { artifact: kind, look: look(kind) };
            app.world_mut().spawn(ItemView { id: ItemId(i), kind: item, place: ItemPlace::InCase(CaseId(i)) });
            app.world_mut().spawn(ItemView { id: ItemId(100 + i), kind: ItemKind::Prop, place: ItemPlace::Carried });
        }
        for (i, alert) in [GuardAlert::Patrolling, GuardAlert::Chasing, GuardAlert::Searching].into_iter().enumerate() {
            app.world_mut().spawn(GuardView {
                id: GuardId(i as u16),
                name: format!("guard {i}"),
                position: Vec2::ZERO,
                facing: 0.0,
                alert,
            });
        }
        app.update();
        let after = counts(&app);
        assert_eq!(after, (before.0 + 2, before.1 + 2), "only the two looks were new: one mesh and material each");
        let dressed = app.world_mut().query_filtered::<(), With<Dressed>>().iter(app.world()).count();
        assert_eq!(dressed, 12 + 24 + 3, "everything was dressed");
    }

    #[test]
    fn a_thrown_item_is_drawn_along_its_arc_from_the_hand_to_where_it_lands() {
        let hand = Vec3::new(2.0, 1.3, -3.0);
        let landing_floor = Vec2::new(8.0, 7.0);
        let mut app = App::new();
        app.insert_resource(ViveState::default())
            .insert_resource(Hands { main: hand, other: hand })
            .insert_resource(Time::<()>::default())
            .add_systems(Update, move_items);
        let item = app
            .world_mut()
            .spawn((
                ItemView { id: ItemId(1), kind: ItemKind::Prop, place: ItemPlace::Carried },
                Drawn { place: ItemPlace::Carried, flight: None },
                Transform::default(),
                Visibility::Hidden,
            ))
            .id();
        let step = |app: &mut App, ms: u64| {
            app.world_mut().resource_mut::<Time>().advance_by(Duration::from_millis(ms));
            app.update();
            app.world().get::<Transform>(item).expect("drawn").translation
        };
        assert_eq!(step(&mut app, 16), hand, "carried: in the hand");
        app.world_mut().get_mut::<ItemView>(item).expect("item").place = ItemPlace::Floor(landing_floor);
        let landing = space::world(landing_floor, 0.08);
        let thrown_at = app.world().resource::<Time>().elapsed_secs_f64() + 0.016;
        let arc = Flight::between(hand, landing, thrown_at);
        let mut drawn = Vec::new();
        for _ in 0..200 {
            drawn.push((app.world().resource::<Time>().elapsed_secs_f64() + 0.016, step(&mut app, 16)));
        }
        let in_air: Vec<_> = drawn.iter().filter(|(t, _)| *t < thrown_at + arc.duration_s as f64).collect();
        assert!(in_air.len() > 30, "it flew for {} frames", in_air.len());
        for (t, p) in &in_air {
            let expected = arc.at(*t).expect("in the air");
            assert!(p.distance(expected) < 1e-4, "at {t:.3} s drawn at {p}, the arc says {expected}");
        }
        assert!(in_air.iter().any(|(_, p)| p.y > hand.y + 1.0), "it rose above the hand");
        assert!(drawn.iter().skip(in_air.len()).all(|(_, p)| *p == landing), "then it lies where it landed");

        // Thrown again and caught mid-air: back in the hand at once.
        app.world_mut().get_mut::<ItemView>(item).expect("item").place = ItemPlace::Carried;
        step(&mut app, 16);
        app.world_mut().get_mut::<ItemView>(item).expect("item").place = ItemPlace::Floor(landing_floor);
        assert_eq!(step(&mut app, 16), hand, "the throw starts from the hand");
        let mid = step(&mut app, 200);
        assert!(mid.y > 1.0 && mid != landing, "in the air again: {mid}");
        app.world_mut().get_mut::<ItemView>(item).expect("item").place = ItemPlace::Carried;
        assert_eq!(step(&mut app, 16), hand, "picked up: no flight left");
    }
}
