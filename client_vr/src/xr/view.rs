//! What XR shows besides the headset's eyes: the desktop window mirrors the left eye; with the bot
//! playing, the room is carried so the headset stands over the bot's body; and the recentring both it
//! and a player's hold use.

use bevy::prelude::*;
use bevy_mod_openxr::helper_traits::{ToQuat, ToVec3};
use bevy_mod_openxr::openxr_session_running;
use bevy_mod_openxr::resources::OxrViews;
use bevy_mod_xr::session::XrTrackingRoot;
use glam::{Vec2, Vec3};

use crate::intent::Intent;
use crate::space;
use crate::state::ViveState;

/// The desktop window's view of what the headset sees (a mirror for onlookers).
#[derive(Component)]
struct Mirror;

/// What XR shows besides the headset's eyes, with or without a player's hands: the desktop window
/// mirrors the left eye (same pose, same vertical field of view); with the bot playing
/// (`follow_body`), the room is carried so the headset stands where the bot's body is and faces its way.
pub struct XrViewPlugin {
    /// Carry the room with the bot's body (no player's head leads it).
    pub follow_body: bool,
}

impl Plugin for XrViewPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_mirror).add_systems(
            PostUpdate,
            mirror_left_eye.after(bevy::transform::TransformSystems::Propagate).run_if(openxr_session_running),
        );
        if self.follow_body {
            app.add_systems(
                Update,
                carry_room_with_body.in_set(crate::client::ViveSystems::Present).run_if(openxr_session_running),
            );
        }
    }
}

fn spawn_mirror(mut commands: Commands) {
    commands.spawn((
        Mirror,
        Camera3d::default(),
        // Drawn before the eyes (their order is 0): one camera to the window, none ambiguous.
        Camera { order: -1, ..default() },
        IsDefaultUiCamera,
        Transform::from_xyz(0.0, space::EYE_HEIGHT_M, 0.0),
    ));
}

/// The mirror's pose and vertical field of view: the left eye's (its world pose after propagation;
/// its field of view from the runtime's view, symmetric about the eye's up–down mid-line).
pub fn left_eye_mirror(eye: &GlobalTransform, angle_up: f32, angle_down: f32) -> (Transform, f32) {
    let (_, rotation, translation) = eye.to_scale_rotation_translation();
    let fov = (angle_up - angle_down).abs().clamp(0.3, 2.6);
    (Transform::from_translation(translation).with_rotation(rotation), fov)
}

fn mirror_left_eye(
    eyes: Query<(&bevy_mod_xr::camera::XrCamera, &GlobalTransform)>,
    views: Option<Res<OxrViews>>,
    mut mirror: Query<
        (&mut Transform, &mut GlobalTransform, &mut Projection),
        (With<Mirror>, Without<bevy_mod_xr::camera::XrCamera>),
    >,
) {
    let Some((_, eye)) = eyes.iter().find(|(c, _)| c.0 == 0) else { return };
    let (up, down) = views.as_ref().and_then(|v| v.first()).map_or((0.7, -0.7), |v| (v.fov.angle_up, v.fov.angle_down));
    let (pose, fov) = left_eye_mirror(eye, up, down);
    for (mut t, mut global, mut projection) in &mut mirror {
        *t = pose;
        *global = GlobalTransform::from(pose); // after propagation: this frame's eye, not last frame's
        if let Projection::Perspective(p) = projection.as_mut() {
            p.fov = fov;
        }
    }
}

/// With the bot playing, keeps the headset over the bot's body, facing its way (the room is moved,
/// as a recentre does, every frame).
fn carry_room_with_body(
    views: Res<OxrViews>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    mut root: Query<&mut Transform, With<XrTrackingRoot>>,
) {
    let (Some(view), Some(body), Ok(mut root)) = (views.first(), state.body(), root.single_mut()) else { return };
    recentre(&mut root, view.pose.position.to_vec3(), view.pose.orientation.to_quat(), body, intent.facing, true);
}

/// Moves the tracking room so the head stands over `body` and looks along `facing`; seated, the view is
/// lifted to standing height.
pub(crate) fn recentre(
    root: &mut Transform,
    head_local: Vec3,
    head_rot_local: Quat,
    body: Vec2,
    facing: f32,
    seated: bool,
) {
    let (head_yaw, _, _) = head_rot_local.to_euler(EulerRot::YXZ);
    let (want_yaw, _, _) = space::rotation(facing).to_euler(EulerRot::YXZ);
    root.rotation = Quat::from_rotation_y(want_yaw - head_yaw);
    let off = root.rotation * head_local;
    let lift = if seated { space::EYE_HEIGHT_M - head_local.y } else { 0.0 };
    let at = space::world(body, lift);
    root.translation = Vec3::new(at.x - off.x, lift, at.z - off.z);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mirror_shows_the_left_eye_from_its_pose_after_this_frames_tracking() {
        use bevy_mod_xr::camera::XrCamera;
        let mut app = App::new();
        app.add_systems(Update, mirror_left_eye);
        let left = Transform::from_xyz(2.0, 1.7, -3.0).with_rotation(Quat::from_rotation_y(0.8));
        let right = Transform::from_xyz(2.06, 1.7, -3.0).with_rotation(Quat::from_rotation_y(0.8));
        app.world_mut().spawn((XrCamera(1), GlobalTransform::from(right)));
        app.world_mut().spawn((XrCamera(0), GlobalTransform::from(left)));
        let mirror = app
            .world_mut()
            .spawn((
                Mirror,
                Transform::default(),
                GlobalTransform::default(),
                Projection::Perspective(PerspectiveProjection::default()),
            ))
            .id();
        app.update();
        let t = *app.world().get::<Transform>(mirror).expect("mirror");
        let g = *app.world().get::<GlobalTransform>(mirror).expect("mirror");
        assert!(t.translation.distance(left.translation) < 1e-5, "at the eye: {}", t.translation);
        assert!(t.rotation.angle_between(left.rotation) < 1e-3, "turned as the eye");
        assert_eq!(g.translation(), left.translation, "drawn from this frame's eye, not last frame's");
        let Some(Projection::Perspective(p)) = app.world().get::<Projection>(mirror) else { panic!("perspective") };
        assert!((p.fov - 1.4).abs() < 1e-6, "without the runtime's views, a 1.4 rad field: {}", p.fov);
        // With the runtime's angles: the eye's whole vertical field.
        let (_, fov) = left_eye_mirror(&GlobalTransform::from(left), 0.8, -0.9);
        assert!((fov - 1.7).abs() < 1e-6);
    }

    #[test]
    fn with_the_bot_playing_the_headset_is_carried_over_its_body_and_faces_its_way() {
        // The runtime's head 0.4 m off the room's centre, 1.2 m up, turned 0.5 rad.
        let head_local = Vec3::new(0.4, 1.2, -0.3);
        let head_rot = Quat::from_rotation_y(0.5);
        let (body, facing) = (Vec2::new(17.0, 6.0), 2.0);
        let mut root = Transform::default();
        recentre(&mut root, head_local, head_rot, body, facing, true);
        let head = root.transform_point(head_local);
        assert!(head.distance(space::world(body, space::EYE_HEIGHT_M)) < 1e-4, "the eyes over the body: {head}");
        assert!((space::facing(root.rotation * head_rot) - facing).abs() < 1e-4, "looking the bot's way");
    }
}
