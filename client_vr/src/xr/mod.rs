//! XR mode: the headset and its controllers through OpenXR (bevy_mod_openxr 0.6).
//!
//! [`probe`] decides at start-up whether XR can run at all (with one log line saying why not). In XR mode
//! `bevy_mod_openxr` renders both eyes from cameras under its tracking root; this module binds one action
//! set for the Vive wands, Oculus Touch and Index controllers and turns the hands into [`Intent`]s:
//!
//! - grip: pick up what the hand is at (the item nearest the hand within reach), hold to carry; release
//!   over the workbench places a copy there, elsewhere it drops;
//! - trigger: with an empty hand, break the case the hand points at; holding an item, throw it on release
//!   — the landing point follows the hand's velocity (ballistic, capped at the throw range);
//! - the off hand's stick (trackpad on a Vive): teleport by default — push to aim an arc ([`arc`]: green
//!   to a valid target, red when refused), release on green and the view blinks dark while the body goes
//!   there under the server's authority; or smooth locomotion with a comfort vignette
//!   (`--locomotion smooth`); clicking it toggles running;
//! - an empty hand rings the item its grip would take;
//! - the main hand's stick: snap turn (30°);
//! - walking in the room moves the body too (the head pulls it); walls hold the view back;
//! - crouching in the room crouches (standing mode); seated mode lifts the view to standing height;
//! - holding both grips with empty hands for 1.5 s recentres;
//! - after a result, a trigger pull asks for another round (as Enter does on the desktop).
//!
//! Controllers pulse on a grab and on breaking glass ([`Pulse`]).

pub mod arc;
pub mod hands;
pub mod probe;
pub mod view;

use std::borrow::Cow;

use bevy::math::Isometry3d;
use bevy::prelude::*;
use bevy_mod_openxr::action_binding::{OxrSendActionBindings, OxrSuggestActionBinding};
use bevy_mod_openxr::action_set_attaching::OxrAttachActionSet;
use bevy_mod_openxr::action_set_syncing::{OxrActionSetSyncSet, OxrSyncActionSet};
use bevy_mod_openxr::helper_traits::{ToQuat, ToVec2, ToVec3};
use bevy_mod_openxr::resources::{OxrInstance, OxrViews};
use bevy_mod_openxr::session::OxrSession;
use bevy_mod_openxr::{openxr_session_available, openxr_session_running};
use bevy_mod_xr::session::{XrPreDestroySession, XrSessionCreated, XrTrackingRoot};
use glam::{Vec2, Vec3};
use heist_shared::protocol::{CaseView, ItemPlace, ItemView};
use openxr::{Action, ActionSet, Haptic, Path, Posef, Vector2f};

pub use arc::TELEPORT_RANGE_M;
pub use hands::{CROUCH_BELOW_M, HEAD_LEASH_M, SNAP_TURN, throw_landing};
pub use probe::{XrProbe, probe, probe_from_env};
pub use view::XrViewPlugin;
use view::recentre;

use crate::client::{Pulse, ViveState};
use crate::intent::{Aim, Intent, IntentSystems};
use crate::space;
use crate::world::Hands;

/// How the sticks move the player.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Locomotion {
    /// Aim an arc and release; the view blinks dark while the body goes there.
    #[default]
    Teleport,
    /// Continuous movement with a comfort vignette.
    Smooth,
}

/// Which hand is the main one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Handedness {
    /// Right-handed.
    #[default]
    Right,
    /// Left-handed.
    Left,
}

/// XR comfort and play settings.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct XrOptions {
    /// Locomotion.
    pub locomotion: Locomotion,
    /// Seated play (no room crouch; view lifted to standing height).
    pub seated: bool,
    /// The main hand.
    pub hand: Handedness,
}

/// The action set and its actions.
#[derive(Resource)]
pub struct XrActions {
    set: ActionSet,
    hands: [Path; 2],
    grip_pose: Action<Posef>,
    aim_pose: Action<Posef>,
    squeeze: Action<bool>,
    trigger: Action<f32>,
    stick: Action<Vector2f>,
    stick_click: Action<bool>,
    talk: Action<bool>,
    haptic: Action<Haptic>,
}

#[derive(Component)]
struct Grip(usize);

#[derive(Component)]
struct Pointer(usize);

#[derive(Component)]
struct Head;

/// The wrist panel showing the HUD.
#[derive(Component)]
struct WristPanel;

/// The fade sphere around the head (teleports).
#[derive(Component)]
struct Comfort;

/// The comfort vignette: a black ring just ahead of the eyes whose opening narrows with smooth motion.
#[derive(Component)]
struct Vignette;

/// The vignette ring's opening at rest and at full speed, metres at [`VIGNETTE_DISTANCE_M`].
pub const VIGNETTE_OPEN_M: (f32, f32) = (0.25, 0.07);
/// How far ahead of the eyes the ring sits, metres.
pub const VIGNETTE_DISTANCE_M: f32 = 0.15;

/// This frame's controls, read from OpenXR: the head and both hands (`hands[0]` left, `hands[1]` right).
#[derive(Resource, Default)]
struct XrInput {
    /// The head was tracked and the actions exist: the rest is this frame's.
    ready: bool,
    /// The head in the tracking room's frame (what the room is recentred by).
    head_local: Vec3,
    head_rot_local: Quat,
    /// The head in the world.
    head: Vec3,
    /// The view's heading, radians.
    facing: f32,
    hands: [hands::HandInput; 2],
    /// Which hand is the main one (its stick turns; the other's moves).
    main: usize,
    /// Seconds since the last frame.
    dt: f32,
}

/// What the hands remember, frame to frame, and what they asked of the view this frame.
#[derive(Resource, Default)]
struct XrHands {
    hands: [hands::HandMemory; 2],
    /// The off hand's stick click toggled running on.
    running: bool,
    /// The main hand's stick snapped the view round by this much this frame, radians.
    turn: f32,
}

/// How the body and the view move, frame to frame (locomotion, the comfort fade and vignette, the
/// recentring hold).
#[derive(Resource, Default)]
struct XrMotion {
    moving: hands::Moving,
    /// The room was recentred on the body once (on joining).
    recentred: bool,
    /// Seconds both grips have been held with empty hands.
    recentre_hold_s: f32,
}

/// The ring around what an empty hand would pick up (one per hand).
#[derive(Component)]
struct GrabHighlight(usize);

/// Radius of the grab highlight ring, metres.
pub const HIGHLIGHT_RADIUS_M: f32 = 0.16;

/// Adds XR input to an app built with `bevy_mod_openxr::add_xr_plugins`.
pub struct XrInputPlugin {
    /// Settings.
    pub options: XrOptions,
}

impl Plugin for XrInputPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(self.options)
            .init_resource::<XrInput>()
            .init_resource::<XrHands>()
            .init_resource::<XrMotion>()
            .insert_resource(bevy::winit::WinitSettings::continuous())
            .add_systems(Startup, create_actions.run_if(openxr_session_available))
            .add_systems(OxrSendActionBindings, suggest_bindings)
            .add_systems(XrSessionCreated, (attach_set, spawn_tracked))
            .add_systems(XrPreDestroySession, despawn_tracked)
            .add_systems(PreUpdate, sync_set.before(OxrActionSetSyncSet).run_if(openxr_session_running))
            .add_systems(
                RunFixedMainLoop,
                (read_hands, use_hands, place_view, walk, comfort)
                    .chain()
                    .in_set(IntentSystems::Gather)
                    .run_if(openxr_session_running),
            )
            .add_systems(Startup, spawn_highlights)
            .add_systems(Update, talk_button.run_if(openxr_session_running))
            .add_systems(
                Update,
                (pulse, strap_wrist_panel, draw_arc, show_grab_highlights.after(crate::world::WorldSystems))
                    .in_set(crate::client::ViveSystems::Present)
                    .run_if(openxr_session_running),
            );
    }
}

fn create_actions(instance: Res<OxrInstance>, mut commands: Commands) {
    let make = || -> openxr::Result<XrActions> {
        let hands = [instance.string_to_path("/user/hand/left")?, instance.string_to_path("/user/hand/right")?];
        let set = instance.create_action_set("heist", "Heist", 0)?;
        Ok(XrActions {
            grip_pose: set.create_action("grip_pose", "Grip pose", &hands)?,
            aim_pose: set.create_action("aim_pose", "Aim pose", &hands)?,
            squeeze: set.create_action("grab", "Grab and carry", &hands)?,
            trigger: set.create_action("use", "Break, throw", &hands)?,
            stick: set.create_action("move", "Teleport, turn", &hands)?,
            stick_click: set.create_action("run", "Run", &hands)?,
            talk: set.create_action("talk", "Talk to Phantom (hold)", &hands)?,
            haptic: set.create_action("pulse", "Pulse", &hands)?,
            hands,
            set,
        })
    };
    match make() {
        Ok(actions) => {
            commands.insert_resource(actions);
        }
        Err(e) => error!("XR: the controller actions could not be created ({e}); controllers will do nothing"),
    }
}

fn both(p: &str) -> Vec<Cow<'static, str>> {
    vec![format!("/user/hand/left{p}").into(), format!("/user/hand/right{p}").into()]
}

fn suggest_bindings(actions: Option<Res<XrActions>>, mut out: MessageWriter<OxrSuggestActionBinding>) {
    let Some(a) = actions else { return };
    // (profile, squeeze, stick, stick click, talk per hand) — every path exists on its hand of its profile.
    for (profile, squeeze, stick, click, talk) in [
        (
            "/interaction_profiles/htc/vive_controller",
            "/input/squeeze/click",
            "/input/trackpad",
            "/input/trackpad/click",
            ["/input/menu/click", "/input/menu/click"],
        ),
        (
            "/interaction_profiles/oculus/touch_controller",
            "/input/squeeze/value",
            "/input/thumbstick",
            "/input/thumbstick/click",
            ["/input/y/click", "/input/b/click"],
        ),
        (
            "/interaction_profiles/valve/index_controller",
            "/input/squeeze/value",
            "/input/thumbstick",
            "/input/thumbstick/click",
            ["/input/b/click", "/input/b/click"],
        ),
    ] {
        out.write(OxrSuggestActionBinding {
            action: a.talk.as_raw(),
            interaction_profile: profile.into(),
            bindings: vec![format!("/user/hand/left{}", talk[0]).into(), format!("/user/hand/right{}", talk[1]).into()],
        });
        let mut bind = |action: openxr::sys::Action, path: &str| {
            out.write(OxrSuggestActionBinding { action, interaction_profile: profile.into(), bindings: both(path) });
        };
        bind(a.grip_pose.as_raw(), "/input/grip/pose");
        bind(a.aim_pose.as_raw(), "/input/aim/pose");
        bind(a.squeeze.as_raw(), squeeze);
        bind(a.trigger.as_raw(), "/input/trigger/value");
        bind(a.stick.as_raw(), stick);
        bind(a.stick_click.as_raw(), click);
        bind(a.haptic.as_raw(), "/output/haptic");
    }
}

/// The walkie-talkie talks while either hand holds its talk button (menu, B or Y).
fn talk_button(actions: Option<Res<XrActions>>, session: Res<OxrSession>, mut talk: ResMut<heist_voice::Talk>) {
    let Some(a) = actions else { return };
    let down = a.hands.iter().any(|h| a.talk.state(&session, *h).is_ok_and(|s| s.current_state));
    if talk.down != down {
        talk.down = down;
    }
}

fn attach_set(actions: Option<Res<XrActions>>, mut out: MessageWriter<OxrAttachActionSet>) {
    if let Some(a) = actions {
        out.write(OxrAttachActionSet(a.set.clone()));
    }
}

fn sync_set(actions: Option<Res<XrActions>>, mut out: MessageWriter<OxrSyncActionSet>) {
    if let Some(a) = actions {
        out.write(OxrSyncActionSet(a.set.clone()));
    }
}

fn spawn_tracked(
    actions: Option<Res<XrActions>>,
    session: Option<Res<OxrSession>>,
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let (Some(a), Some(session)) = (actions, session) else { return };
    let glove = materials.add(StandardMaterial { base_color: Color::srgb(0.2, 0.2, 0.22), ..default() });
    let glove_mesh = meshes.add(Cuboid::new(0.08, 0.04, 0.14));
    match session.create_reference_space(openxr::ReferenceSpaceType::VIEW, Isometry3d::IDENTITY) {
        Ok(head) => {
            let comfort = materials.add(StandardMaterial {
                base_color: Color::srgba(0.0, 0.0, 0.0, 0.0),
                alpha_mode: AlphaMode::Blend,
                unlit: true,
                cull_mode: None,
                ..default()
            });
            let sphere = meshes.add(Sphere::new(0.3));
            let ring = meshes.add(Annulus::new(0.5, 5.0));
            let black = materials.add(StandardMaterial {
                base_color: Color::srgba(0.0, 0.0, 0.0, 0.92),
                alpha_mode: AlphaMode::Blend,
                unlit: true,
                cull_mode: None,
                ..default()
            });
            commands.spawn((head.0, Head)).with_children(|h| {
                h.spawn((Comfort, Mesh3d(sphere), MeshMaterial3d(comfort), Transform::default()));
                h.spawn((
                    Vignette,
                    Mesh3d(ring),
                    MeshMaterial3d(black),
                    Transform::from_xyz(0.0, 0.0, -VIGNETTE_DISTANCE_M)
                        .with_scale(Vec3::splat(VIGNETTE_OPEN_M.0 / 0.5)),
                    Visibility::Hidden,
                ));
            });
        }
        Err(e) => error!("XR: no head space ({e})"),
    }
    for (i, hand) in a.hands.into_iter().enumerate() {
        match session.create_action_space(&a.grip_pose, hand, Isometry3d::IDENTITY) {
            Ok(space) => {
                commands.spawn((space, Grip(i), Mesh3d(glove_mesh.clone()), MeshMaterial3d(glove.clone())));
            }
            Err(e) => error!("XR: no grip space for hand {i} ({e})"),
        }
        match session.create_action_space(&a.aim_pose, hand, Isometry3d::IDENTITY) {
            Ok(space) => {
                commands.spawn((space, Pointer(i)));
            }
            Err(e) => error!("XR: no aim space for hand {i} ({e})"),
        }
    }
}

/// Straps the HUD panel to the off hand's wrist once that hand's grip is tracked.
fn strap_wrist_panel(
    mut commands: Commands,
    grips: Query<(Entity, &Grip)>,
    panels: Query<(), With<WristPanel>>,
    hud: Option<Res<crate::hud::WristHud>>,
    options: Res<XrOptions>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let Some(hud) = hud else { return };
    if !panels.is_empty() {
        return;
    }
    let off = match options.hand {
        Handedness::Right => 0,
        Handedness::Left => 1,
    };
    let Some((grip, _)) = grips.iter().find(|(_, g)| g.0 == off) else { return };
    let material = materials.add(StandardMaterial {
        base_color_texture: Some(hud.image.clone()),
        unlit: true,
        alpha_mode: AlphaMode::Blend,
        cull_mode: None,
        ..default()
    });
    let (w, h) = crate::hud::WRIST_PX;
    let panel = commands
        .spawn((
            WristPanel,
            Mesh3d(meshes.add(Rectangle::new(0.16, 0.16 * h as f32 / w as f32))),
            MeshMaterial3d(material),
            // On the inside of the forearm, tilted towards the eyes.
            Transform::from_xyz(0.0, 0.03, 0.12).with_rotation(Quat::from_rotation_x(-1.0)),
        ))
        .id();
    commands.entity(grip).add_child(panel);
}

fn despawn_tracked(q: Query<Entity, Or<(With<Head>, With<Grip>, With<Pointer>)>>, mut commands: Commands) {
    for e in &q {
        commands.entity(e).despawn();
    }
}

/// The tracked spaces a frame's controls are read from: the runtime's views, the grips, the aims and the
/// tracking room.
#[derive(bevy::ecs::system::SystemParam)]
struct Tracked<'w, 's> {
    views: Res<'w, OxrViews>,
    grips: Query<'w, 's, (&'static Grip, &'static GlobalTransform)>,
    pointers: Query<'w, 's, (&'static Pointer, &'static GlobalTransform)>,
    root: Query<'w, 's, &'static Transform, With<XrTrackingRoot>>,
}

/// Reads the head, the hands' poses and their buttons into [`XrInput`]; shows where the hands are.
fn read_hands(
    actions: Option<Res<XrActions>>,
    session: Res<OxrSession>,
    tracked: Tracked,
    options: Res<XrOptions>,
    time: Res<Time>,
    mut input: ResMut<XrInput>,
    mut hands_out: ResMut<Hands>,
) {
    input.ready = false;
    let (Some(a), Ok(root), Some(view)) = (actions, tracked.root.single(), tracked.views.first()) else { return };
    let head_local = view.pose.position.to_vec3();
    let head_rot_local = view.pose.orientation.to_quat();
    let head = root.transform_point(head_local);
    let head_rot = root.rotation * head_rot_local;
    let facing = space::facing(head_rot);
    let main = match options.hand {
        Handedness::Right => 1,
        Handedness::Left => 0,
    };
    let mut hands = [hands::HandInput {
        position: head,
        pointing: Vec2::new(facing.cos(), facing.sin()),
        aim_from: head,
        aim_along: head_rot * Vec3::NEG_Z,
        ..Default::default()
    }; 2];
    for (g, t) in &tracked.grips {
        hands[g.0.min(1)].position = t.translation();
    }
    for (p, t) in &tracked.pointers {
        let hand = &mut hands[p.0.min(1)];
        let forward = t.forward().as_vec3();
        (hand.aim_from, hand.aim_along) = (t.translation(), forward);
        let f = space::floor(forward);
        if f.length() > 0.1 {
            hand.pointing = f;
        }
    }
    for (hand, path) in hands.iter_mut().zip(a.hands) {
        hand.squeeze = a.squeeze.state(&session, path).map(|s| s.current_state).unwrap_or(false);
        hand.trigger = a.trigger.state(&session, path).map(|s| s.current_state).unwrap_or(0.0) > hands::TRIGGER_PULLED;
        hand.stick = a.stick.state(&session, path).map(|s| s.current_state.to_vec2()).unwrap_or_default();
        hand.click = a.stick_click.state(&session, path).is_ok_and(|s| s.current_state && s.changed_since_last_sync);
    }
    hands_out.main = hands[main].position;
    hands_out.other = hands[1 - main].position;
    *input =
        XrInput { ready: true, head_local, head_rot_local, head, facing, hands, main, dt: time.delta_secs().max(1e-4) };
}

/// What each hand does (`hands::decide_hand`): the server's actions, running toggled, the view turned.
fn use_hands(
    input: Res<XrInput>,
    mut memory: ResMut<XrHands>,
    mut intent: ResMut<Intent>,
    state: Res<ViveState>,
    cases: Query<&CaseView>,
    items: Query<&ItemView>,
) {
    memory.turn = 0.0;
    if !input.ready || state.body().is_none() {
        return;
    }
    intent.facing = input.facing;
    let case_refs: Vec<&CaseView> = cases.iter().collect();
    let bench = state.level.as_ref().map(|l| l.workbench);
    for hand in 0..2 {
        let control = &input.hands[hand];
        let aim = Aim { from: space::floor(control.position), towards: control.pointing };
        let held = memory.hands[hand].holding;
        let around = hands::AroundHand {
            phase: state.phase,
            item: aim.item(items.iter(), &case_refs),
            case: if control.trigger { aim.case(cases.iter()) } else { None },
            bench,
            held_taken: held.is_some_and(|id| items.iter().any(|i| i.id == id && i.place != ItemPlace::Carried)),
        };
        let out = hands::decide_hand(&mut memory.hands[hand], control, &around, hand == input.main, input.dt);
        intent.actions.extend(out.actions);
        if out.toggle_running {
            memory.running = !memory.running;
        }
        memory.turn += out.turn.unwrap_or(0.0);
    }
}

/// Keeps the view on the body: recentred on joining and on the recentring hold, carried with the body
/// the sticks moved, turned by the main stick.
fn place_view(
    input: Res<XrInput>,
    memory: Res<XrHands>,
    mut motion: ResMut<XrMotion>,
    state: Res<ViveState>,
    options: Res<XrOptions>,
    mut root: Query<&mut Transform, With<XrTrackingRoot>>,
) {
    let (true, Some(body), Ok(mut root)) = (input.ready, state.body(), root.single_mut()) else { return };
    let recentre_here = |root: &mut Transform| {
        recentre(root, input.head_local, input.head_rot_local, body, input.facing, options.seated)
    };
    // Keep the body under the head: on joining, recentre on the body.
    if !motion.recentred {
        recentre_here(&mut root);
        motion.recentred = true;
    }
    // The body moved because of the sticks: carry the room along.
    if let Some(d) = hands::carry(&mut motion.moving, body) {
        root.translation += space::world(d, 0.0);
    }
    if memory.turn != 0.0 {
        root.rotate_around(input.head, Quat::from_rotation_y(memory.turn));
    }
    if hands::hold_to_recentre(&memory.hands, &mut motion.recentre_hold_s, input.dt) {
        recentre_here(&mut root);
    }
}

/// Moves the body: the off hand's stick (smooth, or a teleport arc), the head leading it; walls hold the
/// view back.
fn walk(
    input: Res<XrInput>,
    memory: Res<XrHands>,
    mut motion: ResMut<XrMotion>,
    mut intent: ResMut<Intent>,
    state: Res<ViveState>,
    options: Res<XrOptions>,
    mut root: Query<&mut Transform, With<XrTrackingRoot>>,
) {
    let (true, Some(body), Ok(mut root)) = (input.ready, state.body(), root.single_mut()) else { return };
    let off = &input.hands[1 - input.main];
    let stick = memory.hands[1 - input.main].stick_was;
    let standing = hands::Standing {
        facing: input.facing,
        head: input.head,
        body,
        seated: options.seated,
        smooth: options.locomotion == Locomotion::Smooth,
        running: memory.running,
        dt: input.dt,
    };
    let aimed = match (&state.level, &state.walls) {
        (Some(level), Some(walls)) if !standing.smooth && hands::aiming(stick) => {
            Some(arc::teleport_arc(off.aim_from, off.aim_along, body, level, walls))
        }
        _ => None,
    };
    let step = hands::decide_move(&mut motion.moving, stick, &standing, aimed);
    intent.movement = step.movement;
    intent.gait = step.gait;
    if let Some(back) = step.leash {
        root.translation -= space::world(back, 0.0);
    }
}

/// Draws the teleport arc while aiming: green to a valid target (with a ring where the body will
/// stand), red and ending where it is refused.
fn draw_arc(motion: Res<XrMotion>, mut gizmos: Gizmos) {
    let Some(aimed) = motion.moving.arc.as_ref() else { return };
    let colour = if aimed.valid() { Color::srgb(0.2, 1.0, 0.4) } else { Color::srgb(1.0, 0.2, 0.15) };
    gizmos.linestrip(aimed.points.iter().copied(), colour);
    let ring = Isometry3d::new(space::world(aimed.landing, 0.02), Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2));
    gizmos.circle(ring, heist_shared::rules::BODY_RADIUS, colour);
}

fn spawn_highlights(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let ring = meshes.add(Torus::new(HIGHLIGHT_RADIUS_M - 0.01, HIGHLIGHT_RADIUS_M + 0.01));
    let glow = materials.add(StandardMaterial {
        base_color: Color::srgb(1.0, 0.9, 0.4),
        emissive: LinearRgba::rgb(4.0, 3.2, 1.0),
        unlit: true,
        ..default()
    });
    for hand in 0..2 {
        commands.spawn((
            GrabHighlight(hand),
            Mesh3d(ring.clone()),
            MeshMaterial3d(glow.clone()),
            Transform::default(),
            Visibility::Hidden,
        ));
    }
}

/// Puts each hand's highlight ring around the item it would pick up, where that item is drawn; hides it
/// when the hand holds something or reaches nothing.
fn show_grab_highlights(
    memory: Res<XrHands>,
    items: Query<(&ItemView, &Transform), Without<GrabHighlight>>,
    mut rings: Query<(&GrabHighlight, &mut Transform, &mut Visibility)>,
) {
    for (hand, mut t, mut vis) in &mut rings {
        let target = memory.hands[hand.0.min(1)].grabbable.and_then(|id| items.iter().find(|(i, _)| i.id == id));
        match target {
            Some((_, at)) => {
                t.translation = at.translation;
                *vis = Visibility::Inherited;
            }
            None => *vis = Visibility::Hidden,
        }
    }
}

/// The opening of the vignette ring for smooth motion at `strength` (0 at rest, 1 at full speed), metres.
pub fn vignette_opening(strength: f32) -> f32 {
    let (rest, full) = VIGNETTE_OPEN_M;
    rest + (full - rest) * strength.clamp(0.0, 1.0)
}

fn comfort(
    motion: Res<XrMotion>,
    q: Query<&MeshMaterial3d<StandardMaterial>, With<Comfort>>,
    mut ring: Query<(&mut Transform, &mut Visibility), With<Vignette>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    for (mut t, mut vis) in &mut ring {
        let vignette = motion.moving.vignette;
        t.scale = Vec3::splat(vignette_opening(vignette) / 0.5);
        *vis = if vignette > 0.05 { Visibility::Inherited } else { Visibility::Hidden };
    }
    for m in &q {
        if let Some(mut mat) = materials.get_mut(&m.0) {
            let alpha = motion.moving.fade.clamp(0.0, 0.95);
            if (mat.base_color.alpha() - alpha).abs() > 0.01 {
                mat.base_color = Color::srgba(0.0, 0.0, 0.0, alpha);
            }
        }
    }
}

fn pulse(
    actions: Option<Res<XrActions>>,
    session: Res<OxrSession>,
    options: Res<XrOptions>,
    mut pulses: MessageReader<Pulse>,
) {
    let Some(a) = actions else { return };
    let main = match options.hand {
        Handedness::Right => a.hands[1],
        Handedness::Left => a.hands[0],
    };
    for p in pulses.read() {
        let v = openxr::HapticVibration::new()
            .amplitude(p.amplitude.clamp(0.0, 1.0))
            .frequency(openxr::FREQUENCY_UNSPECIFIED)
            .duration(openxr::Duration::from_nanos((p.seconds * 1e9) as i64));
        if let Err(e) = a.haptic.apply_feedback(&session, main, &v) {
            warn!("XR: controller pulse failed ({e})");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::rules;

    #[test]
    fn each_empty_hand_rings_what_it_would_pick_up_where_that_is_drawn() {
        use heist_shared::protocol::{ItemId, ItemKind};
        let mut app = App::new();
        app.init_resource::<XrHands>().add_systems(Update, show_grab_highlights);
        let at = Vec3::new(3.0, 1.1, -4.0);
        app.world_mut().spawn((
            ItemView { id: ItemId(7), kind: ItemKind::Prop, place: ItemPlace::Floor(Vec2::new(3.0, 4.0)) },
            Transform::from_translation(at),
        ));
        let rings: Vec<Entity> = (0..2)
            .map(|h| app.world_mut().spawn((GrabHighlight(h), Transform::default(), Visibility::Hidden)).id())
            .collect();
        let shown = |app: &App| {
            rings
                .iter()
                .map(|r| {
                    let vis = *app.world().get::<Visibility>(*r).expect("ring");
                    (vis != Visibility::Hidden).then(|| app.world().get::<Transform>(*r).expect("ring").translation)
                })
                .collect::<Vec<_>>()
        };
        app.world_mut().resource_mut::<XrHands>().hands[1].grabbable = Some(ItemId(7));
        app.update();
        assert_eq!(shown(&app), vec![None, Some(at)], "the right hand's ring is round the item");
        let mut memory = app.world_mut().resource_mut::<XrHands>();
        (memory.hands[0].grabbable, memory.hands[1].grabbable) = (Some(ItemId(9)), None);
        app.update();
        assert_eq!(shown(&app), vec![None, None], "an item not drawn is not ringed; an empty reach shows nothing");
    }

    #[test]
    fn the_vignette_narrows_with_speed() {
        assert_eq!(vignette_opening(0.0), VIGNETTE_OPEN_M.0);
        assert!((vignette_opening(1.0) - VIGNETTE_OPEN_M.1).abs() < 1e-6);
        assert!(vignette_opening(0.5) < VIGNETTE_OPEN_M.0 && vignette_opening(0.5) > VIGNETTE_OPEN_M.1);
        assert!((vignette_opening(3.0) - VIGNETTE_OPEN_M.1).abs() < 1e-6, "clamped");
    }

    #[test]
    fn a_throw_lands_along_the_hands_velocity_within_range() {
        // From 1.2 m, thrown level at 4 m/s towards −z (north): about 2 m north.
        let at = throw_landing(Vec3::new(0.0, 1.2, 0.0), Vec3::new(0.0, 0.0, -4.0));
        assert!(at.x.abs() < 1e-5 && (at.y - 4.0 * (2.0 * 1.2 / 9.81f32).sqrt()).abs() < 1e-3, "{at}");
        // A hard throw is capped at the range.
        let far = throw_landing(Vec3::new(0.0, 1.5, 0.0), Vec3::new(30.0, 5.0, 0.0));
        assert!((far.length() - rules::THROW_RANGE).abs() < 1e-3, "{far}");
        // Dropped (no velocity): lands under the hand.
        assert_eq!(throw_landing(Vec3::new(2.0, 1.0, -3.0), Vec3::ZERO), Vec2::new(2.0, 3.0));
    }
}
