//! Desktop mode: keyboard and mouse, a first-person camera at the predicted body.
//!
//! WASD walk, mouse looks (click to capture the cursor, Esc frees it), Shift runs, Ctrl crouches,
//! left mouse picks up the item in front or throws what is carried where you look, E breaks the case
//! in front, F places a carried copy on the workbench, Q drops, Enter says ready.

use bevy::input::mouse::AccumulatedMouseMotion;
use bevy::prelude::*;
use bevy::window::{CursorGrabMode, CursorOptions, PrimaryWindow};
use glam::{Vec2, Vec3};
use heist_shared::protocol::{CaseView, Gait, ItemKind, ItemView, Phase};
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
            app.add_systems(RunFixedMainLoop, (capture_cursor, look, keys).chain().in_set(IntentSystems::Gather));
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

#[allow(clippy::too_many_arguments)]
fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    buttons: Res<ButtonInput<MouseButton>>,
    cursor: Query<&CursorOptions, With<PrimaryWindow>>,
    view: Res<Look>,
    mut intent: ResMut<Intent>,
    state: Res<ViveState>,
    cases: Query<&CaseView>,
    items: Query<&ItemView>,
) {
    intent.movement = walk_direction(
        keys.pressed(KeyCode::KeyW),
        keys.pressed(KeyCode::KeyS),
        keys.pressed(KeyCode::KeyA),
        keys.pressed(KeyCode::KeyD),
        intent.facing,
    );
    intent.gait = if keys.any_pressed([KeyCode::ControlLeft, KeyCode::ControlRight]) {
        Gait::Crouch
    } else if keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]) {
        Gait::Run
    } else {
        Gait::Walk
    };
    if keys.just_pressed(KeyCode::Enter)
        && let Some(action) = enter_action(state.phase)
    {
        intent.actions.push(action);
    }
    let Some(body) = state.body() else { return };
    let aim = Aim { from: body, towards: Vec2::new(intent.facing.cos(), intent.facing.sin()) };
    let case_refs: Vec<&CaseView> = cases.iter().collect();
    if keys.just_pressed(KeyCode::KeyE)
        && let Some(case) = aim.case(cases)
    {
        intent.actions.push(Action::Break(case));
    }
    // The first click only captures the cursor.
    let captured = cursor.single().is_ok_and(|c| c.grab_mode != CursorGrabMode::None);
    if buttons.just_pressed(MouseButton::Left) && captured {
        let hands_full = state.carrying.len() >= rules::CARRY_LIMIT;
        match (hands_full, aim.item(items.iter(), &case_refs), state.carrying.first()) {
            (false, Some(item), _) => intent.actions.push(Action::PickUp(item)),
            (_, _, Some(&item)) => {
                // Throw where the view meets the floor.
                let down = (-view.pitch).max(0.05);
                let distance = space::EYE_HEIGHT_M / down.tan();
                intent.actions.push(Action::Throw { item, target: aim.throw_target(distance) });
            }
            _ => {}
        }
    }
    if keys.just_pressed(KeyCode::KeyF) {
        let copy = state
            .carrying
            .iter()
            .copied()
            .find(|c| items.iter().any(|i| i.id == *c && matches!(i.kind, ItemKind::Copy { .. })));
        if let Some(item) = copy {
            intent.actions.push(Action::Place(item));
        }
    }
    if keys.just_pressed(KeyCode::KeyQ)
        && let Some(&item) = state.carrying.last()
    {
        intent.actions.push(Action::Drop(item));
    }
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
