//! The museum floor (the server's 2-D plane, metres, +y north) in Bevy's 3-D world (+y up, −z north).

use glam::{Quat, Vec2, Vec3};

/// Eye height of a standing player, metres.
pub const EYE_HEIGHT_M: f32 = 1.6;
/// Eye height when crouching, metres.
pub const CROUCH_EYE_HEIGHT_M: f32 = 1.0;
/// Height of the workbench top, metres.
pub const BENCH_TOP_M: f32 = 0.9;

/// Floor point `p` at height `h`.
pub fn world(p: Vec2, h: f32) -> Vec3 {
    Vec3::new(p.x, h, -p.y)
}

/// The floor point under a world point.
pub fn floor(v: Vec3) -> Vec2 {
    Vec2::new(v.x, -v.z)
}

/// The rotation that turns Bevy's forward (−z) to floor angle `facing` (radians from +x, counter-clockwise).
pub fn rotation(facing: f32) -> Quat {
    Quat::from_rotation_y(facing - std::f32::consts::FRAC_PI_2)
}

/// The floor angle a world rotation faces (its forward projected on the floor).
pub fn facing(rotation: Quat) -> f32 {
    let f = floor(rotation * Vec3::NEG_Z);
    f.y.atan2(f.x)
}

/// The offset of floor point `p` at height `h` from a listener at `at`, ears at `ears_m`, facing `facing`,
/// in the listener's frame (+x right, +y up, −z ahead) — what `heist_audio` places sounds with.
pub fn listener_offset(at: Vec2, facing: f32, ears_m: f32, p: Vec2, h: f32) -> Vec3 {
    let d = p - at;
    let ahead = Vec2::new(facing.cos(), facing.sin());
    let right = Vec2::new(facing.sin(), -facing.cos());
    Vec3::new(d.dot(right), h - ears_m, -d.dot(ahead))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    #[test]
    fn floor_and_world_agree() {
        let p = Vec2::new(3.0, 4.0);
        assert_eq!(floor(world(p, 1.0)), p);
        // Facing north (+y on the floor) looks along −z.
        assert!((rotation(FRAC_PI_2) * Vec3::NEG_Z).distance(Vec3::NEG_Z) < 1e-6);
        // Facing east (+x) looks along +x.
        assert!((rotation(0.0) * Vec3::NEG_Z).distance(Vec3::X) < 1e-6);
        for a in [-2.0f32, -0.3, 0.0, 1.0, 2.5] {
            assert!((facing(rotation(a)) - a).abs() < 1e-5);
        }
    }

    #[test]
    fn sounds_are_placed_in_the_listeners_frame() {
        // Facing east, a source to the north is on the left; one to the east is ahead.
        let left = listener_offset(Vec2::ZERO, 0.0, 1.6, Vec2::new(0.0, 2.0), 1.6);
        assert!((left - Vec3::new(-2.0, 0.0, 0.0)).length() < 1e-5, "{left}");
        let ahead = listener_offset(Vec2::ZERO, 0.0, 1.6, Vec2::new(3.0, 0.0), 0.0);
        assert!((ahead - Vec3::new(0.0, -1.6, -3.0)).length() < 1e-5, "{ahead}");
        // Facing north matches heist_audio's north-facing helper.
        let p = Vec2::new(1.0, 5.0);
        assert!(
            (listener_offset(Vec2::ZERO, FRAC_PI_2, 1.6, p, 0.0) - heist_audio::listener_offset(Vec2::ZERO, p, 0.0))
                .length()
                < 1e-5
        );
    }
}
