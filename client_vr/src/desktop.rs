//! Desktop mode: keyboard and mouse, a first-person camera at the predicted body.
//!
//! WASD walk, mouse looks (click to capture the cursor, Esc frees it), Shift runs, Ctrl crouches,
//! left mouse picks up the item in front or throws what is carried where you look, E breaks the case
//! in front, F places a carried copy on the workbench, Q drops, Enter says ready.

use bevy::input::mouse::AccumulatedMouseMotion;
use bevy::prelude::*;
use bevy::window::{CursorGrabMode, CursorOptions, PrimaryWindow};
use glam::{Vec2, Vec3};
use heist_shared::protocol::{CaseId, CaseView, Gait, ItemId, ItemKind, ItemView, Phase};
use heist_shared::rules;

use crate::client::{ViveState, ViveSystems};
use crate::intent::{Action, Aim, Intent, IntentSystems};
use crate::space;
use crate::world::Hands;

/// Mouse sensitivity, radians per pixel.
pub const SENSITIVITY: f32 = 0.003;

/// The player's camera (desktop mode).
#[derive(Component)]
pub struct PlayerCamera;

/// Where the player looks: yaw is the intent's facing, pitch is the camera's.
#[derive(Resource, Clone, Copy, Debug)]
pub struct Look {
    /// Up/down, radians (negative looks down).
    pub pitch: f32,
}

impl Default for Look {
    fn default() -> Self {
        Self { pitch: -0.12 }
    }
}

/// The first-person camera, and keyboard and mouse when they drive the player.
pub struct DesktopPlugin {
    /// Keyboard and mouse write the intents (off when the bot plays and the window only watches).
    pub input: bool,
}

impl Plugin for DesktopPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Look>()
            .add_systems(Startup, spawn_camera)
            .add_systems(Update, follow_body.in_set(ViveSystems::Present).before(crate::world::WorldSystems));
        if self.input {
            app.init_resource::<DesktopInput>().add_systems(
                RunFixedMainLoop,
                (capture_cursor, look, read_keys, use_keys).chain().in_set(IntentSystems::Gather),
            );
        }
    }
}

/// The desktop camera's vertical field of view, degrees.
pub const FOV_DEG: f32 = 70.0;

fn spawn_camera(mut commands: Commands) {
    commands.spawn((
        PlayerCamera,
        Camera3d::default(),
        Projection::Perspective(PerspectiveProjection { fov: FOV_DEG.to_radians(), ..default() }),
        Transform::from_xyz(0.0, space::EYE_HEIGHT_M, 0.0),
    ));
}

fn capture_cursor(
    mut cursor: Query<&mut CursorOptions, With<PrimaryWindow>>,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
) {
    let Ok(mut cursor) = cursor.single_mut() else { return };
    if buttons.just_pressed(MouseButton::Left) && cursor.grab_mode == CursorGrabMode::None {
        cursor.grab_mode = CursorGrabMode::Locked;
        cursor.visible = false;
    }
    if keys.just_pressed(KeyCode::Escape) {
        cursor.grab_mode = CursorGrabMode::None;
        cursor.visible = true;
    }
}

fn look(
    motion: Res<AccumulatedMouseMotion>,
    cursor: Query<&CursorOptions, With<PrimaryWindow>>,
    mut view: ResMut<Look>,
    mut intent: ResMut<Intent>,
) {
    let captured = cursor.single().is_ok_and(|c| c.grab_mode != CursorGrabMode::None);
    if !captured || motion.delta == Vec2::ZERO {
        return;
    }
    intent.facing = (intent.facing - motion.delta.x * SENSITIVITY).rem_euclid(std::f32::consts::TAU);
    view.pitch = (view.pitch - motion.delta.y * SENSITIVITY).clamp(-1.4, 1.4);
}

/// What Enter means in `phase`: ready in the lobby, another round after a result, nothing mid-heist.
pub fn enter_action(phase: Phase) -> Option<Action> {
    match phase {
        Phase::Lobby => Some(Action::Ready),
        Phase::Won | Phase::Lost(_) => Some(Action::Rematch),
        Phase::Heist => None,
    }
}

/// The walking direction on the floor for pressed keys, facing `facing`.
pub fn walk_direction(forward: bool, back: bool, left: bool, right: bool, facing: f32) -> Vec2 {
    let ahead = Vec2::new(facing.cos(), facing.sin());
    let side = Vec2::new(facing.sin(), -facing.cos());
    let f = f32::from(u8::from(forward)) - f32::from(u8::from(back));
    let s = f32::from(u8::from(right)) - f32::from(u8::from(left));
    (ahead * f + side * s).normalize_or_zero()
}

/// This frame's keyboard and mouse, as the desktop player uses them.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct DesktopInput {
    /// W, S, A, D held: forward, back, left, right.
    pub walk: [bool; 4],
    /// Ctrl held.
    pub crouch: bool,
    /// Shift held.
    pub run: bool,
    /// Enter pressed.
    pub enter: bool,
    /// E pressed: break.
    pub break_case: bool,
    /// The left button clicked with the cursor captured (the first click only captures it).
    pub click: bool,
    /// F pressed: place.
    pub place: bool,
    /// Q pressed: drop.
    pub drop: bool,
}

/// Where the desktop player stands, as far as the keys care.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DesktopSituation<'a> {
    /// The session's phase.
    pub phase: Phase,
    /// The view's heading, radians.
    pub facing: f32,
    /// The view's pitch, radians (negative looks down).
    pub pitch: f32,
    /// The body is placed (the level arrived).
    pub placed: bool,
    /// What Vive carries, oldest first.
    pub carrying: &'a [ItemId],
    /// The item in front, within reach.
    pub item_ahead: Option<ItemId>,
    /// The unbroken case in front, within reach.
    pub case_ahead: Option<CaseId>,
    /// A carried copy (the first), for the workbench.
    pub carried_copy: Option<ItemId>,
    /// Where the body is (throws start there).
    pub body: Vec2,
}

/// What the desktop player's input asks for: how to walk, and the actions for the server in order.
pub fn decide(input: &DesktopInput, at: &DesktopSituation) -> (Vec2, Gait, Vec<Action>) {
    let [forward, back, left, right] = input.walk;
    let movement = walk_direction(forward, back, left, right, at.facing);
    let gait = if input.crouch {
        Gait::Crouch
    } else if input.run {
        Gait::Run
    } else {
        Gait::Walk
    };
    let mut actions = Vec::new();
    if input.enter
        && let Some(action) = enter_action(at.phase)
    {
        actions.push(action);
    }
    if !at.placed {
        return (movement, gait, actions);
    }
    if input.break_case
        && let Some(case) = at.case_ahead
    {
        actions.push(Action::Break(case));
    }
    if input.click {
        let hands_full = at.carrying.len() >= rules::CARRY_LIMIT;
        match (hands_full, at.item_ahead, at.carrying.first()) {
            (false, Some(item), _) => actions.push(Action::PickUp(item)),
            (_, _, Some(&item)) => {
                // Throw where the view meets the floor.
                let down = (-at.pitch).max(0.05);
                let distance = space::EYE_HEIGHT_M / down.tan();
                let aim = Aim { from: at.body, towards: Vec2::new(at.facing.cos(), at.facing.sin()) };
                actions.push(Action::Throw { item, target: aim.throw_target(distance) });
            }
            _ => {}
        }
    }
    if input.place
        && let Some(item) = at.carried_copy
    {
        actions.push(Action::Place(item));
    }
    if input.drop
        && let Some(&item) = at.carrying.last()
    {
        actions.push(Action::Drop(item));
    }
    (movement, gait, actions)
}

/// Reads the keyboard and the mouse's buttons into [`DesktopInput`].
fn read_keys(
    keys: Res<ButtonInput<KeyCode>>,
    buttons: Res<ButtonInput<MouseButton>>,
    cursor: Query<&CursorOptions, With<PrimaryWindow>>,
    mut input: ResMut<DesktopInput>,
) {
    let captured = cursor.single().is_ok_and(|c| c.grab_mode != CursorGrabMode::None);
    *input = DesktopInput {
        walk: [KeyCode::KeyW, KeyCode::KeyS, KeyCode::KeyA, KeyCode::KeyD].map(|k| keys.pressed(k)),
        crouch: keys.any_pressed([KeyCode::ControlLeft, KeyCode::ControlRight]),
        run: keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]),
        enter: keys.just_pressed(KeyCode::Enter),
        break_case: keys.just_pressed(KeyCode::KeyE),
        click: buttons.just_pressed(MouseButton::Left) && captured,
        place: keys.just_pressed(KeyCode::KeyF),
        drop: keys.just_pressed(KeyCode::KeyQ),
    };
}

/// Turns the desktop input into the intent (see [`decide`]).
fn use_keys(
    input: Res<DesktopInput>,
    view: Res<Look>,
    mut intent: ResMut<Intent>,
    state: Res<ViveState>,
    cases: Query<&CaseView>,
    items: Query<&ItemView>,
) {
    let body = state.body();
    let aim = Aim { from: body.unwrap_or_default(), towards: Vec2::new(intent.facing.cos(), intent.facing.sin()) };
    let case_refs: Vec<&CaseView> = cases.iter().collect();
    let situation = DesktopSituation {
        phase: state.phase,
        facing: intent.facing,
        pitch: view.pitch,
        placed: body.is_some(),
        carrying: &state.carrying,
        item_ahead: body.and_then(|_| aim.item(items.iter(), &case_refs)),
        case_ahead: body.and_then(|_| aim.case(cases.iter())),
        carried_copy: state
            .carrying
            .iter()
            .copied()
            .find(|c| items.iter().any(|i| i.id == *c && matches!(i.kind, ItemKind::Copy { .. }))),
        body: body.unwrap_or_default(),
    };
    let (movement, gait, actions) = decide(&input, &situation);
    intent.movement = movement;
    intent.gait = gait;
    intent.actions.extend(actions);
}

/// The camera sits at the body's predicted position, eyes lower when crouching; carried items are held
/// low in front.
fn follow_body(
    mut camera: Query<&mut Transform, With<PlayerCamera>>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    view: Res<Look>,
    mut hands: ResMut<Hands>,
    time: Res<Time>,
    mut eyes: Local<Option<f32>>,
) {
    let Ok(mut t) = camera.single_mut() else { return };
    let body = state.body().or(state.level.as_ref().map(|l| l.vive_spawn)).unwrap_or_default();
    let want = if intent.gait == Gait::Crouch { space::CROUCH_EYE_HEIGHT_M } else { space::EYE_HEIGHT_M };
    let h = eyes.get_or_insert(want);
    *h += (want - *h) * (time.delta_secs() * 10.0).min(1.0);
    t.translation = space::world(body, *h);
    t.rotation = space::rotation(intent.facing) * Quat::from_rotation_x(view.pitch);
    hands.main = t.transform_point(Vec3::new(0.25, -0.3, -0.5));
    hands.other = t.transform_point(Vec3::new(-0.25, -0.3, -0.5));
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    fn heist<'a>(carrying: &'a [ItemId], item_ahead: Option<u16>, case_ahead: Option<u16>) -> DesktopSituation<'a> {
        DesktopSituation {
            phase: Phase::Heist,
            facing: FRAC_PI_2,
            pitch: -0.3,
            placed: true,
            carrying,
            item_ahead: item_ahead.map(ItemId),
            case_ahead: case_ahead.map(CaseId),
            carried_copy: None,
            body: Vec2::new(5.0, 5.0),
        }
    }

    #[test]
    fn wasd_walks_the_way_the_view_faces_shift_runs_and_ctrl_crouches() {
        let forward = DesktopInput { walk: [true, false, false, false], run: true, ..Default::default() };
        let (movement, gait, actions) = decide(&forward, &heist(&[], None, None));
        assert!((movement - Vec2::Y).length() < 1e-5 && gait == Gait::Run && actions.is_empty());
        let crouching = DesktopInput { crouch: true, run: true, ..Default::default() };
        assert_eq!(decide(&crouching, &heist(&[], None, None)).1, Gait::Crouch, "crouching wins over running");
    }

    #[test]
    fn a_click_picks_up_the_item_in_front_and_with_full_hands_throws_where_the_view_meets_the_floor() {
        let click = DesktopInput { click: true, ..Default::default() };
        assert_eq!(decide(&click, &heist(&[], Some(4), None)).2, [Action::PickUp(ItemId(4))]);
        let full = [ItemId(1), ItemId(2)];
        let (_, _, actions) = decide(&click, &heist(&full, Some(4), None));
        let [Action::Throw { item, target }] = actions.as_slice() else { panic!("a throw: {actions:?}") };
        let ahead = space::EYE_HEIGHT_M / 0.3f32.tan();
        assert_eq!(*item, ItemId(1));
        assert!((*target - Vec2::new(5.0, 5.0 + ahead)).length() < 1e-3, "{target}");
    }

    #[test]
    fn e_breaks_the_case_in_front_f_places_a_carried_copy_and_q_drops_the_last_item() {
        let keys = DesktopInput { break_case: true, place: true, drop: true, ..Default::default() };
        let carrying = [ItemId(1), ItemId(2)];
        let situation = DesktopSituation { carried_copy: Some(ItemId(2)), ..heist(&carrying, None, Some(3)) };
        assert_eq!(
            decide(&keys, &situation).2,
            [Action::Break(CaseId(3)), Action::Place(ItemId(2)), Action::Drop(ItemId(2))]
        );
    }

    #[test]
    fn before_the_body_is_placed_only_enter_and_walking_count() {
        let keys = DesktopInput { enter: true, break_case: true, click: true, ..Default::default() };
        let lobby = DesktopSituation { phase: Phase::Lobby, placed: false, ..heist(&[], Some(1), Some(1)) };
        assert_eq!(decide(&keys, &lobby).2, [Action::Ready]);
    }

    #[test]
    fn enter_readies_in_the_lobby_and_asks_for_another_round_after_a_result() {
        use heist_shared::protocol::{ClientMsg, LobbyMsg, LossReason};
        assert_eq!(enter_action(Phase::Lobby).map(Action::message), Some(ClientMsg::Lobby(LobbyMsg::Ready)));
        assert_eq!(enter_action(Phase::Won).map(Action::message), Some(ClientMsg::Lobby(LobbyMsg::Rematch)));
        assert_eq!(enter_action(Phase::Lost(LossReason::Caught)), Some(Action::Rematch));
        assert_eq!(enter_action(Phase::Heist), None);
    }

    #[test]
    fn wasd_moves_relative_to_where_the_player_looks() {
        // Facing north: W goes north, D goes east.
        assert!(walk_direction(true, false, false, false, FRAC_PI_2).distance(Vec2::Y) < 1e-6);
        assert!(walk_direction(false, false, false, true, FRAC_PI_2).distance(Vec2::X) < 1e-6);
        // Facing east: A goes north; diagonals are not faster.
        assert!(walk_direction(false, false, true, false, 0.0).distance(Vec2::Y) < 1e-6);
        assert!((walk_direction(true, false, true, false, 0.3).length() - 1.0).abs() < 1e-6);
        assert_eq!(walk_direction(true, true, false, false, 0.0), Vec2::ZERO);
    }
}
