//! The scripted tool path of the bunny benchmark: 35 s at 1 kHz, bunny fixed at the identity pose.

use crate::shape::TriMesh;
use glam::{EulerRot, Quat, Vec3};
use haptic_common::Pose;
use std::f32::consts::TAU;

/// Length of the scripted path, seconds.
pub const TRAJECTORY_SECONDS: f64 = 35.0;
/// Sampling rate of the path, Hz.
pub const TRAJECTORY_RATE_HZ: u32 = 1000;

/// What the script intends in a stretch of the path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Phase {
    /// The tool is away from the bunny (about 3 cm out).
    Free,
    /// The tool slides along the surface, penetrating up to about 2 mm.
    Grazing,
    /// The tool is pushed 1–3 cm into the bunny.
    Deep,
}

impl Phase {
    /// Lower-case name used in CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Free => "free",
            Phase::Grazing => "grazing",
            Phase::Deep => "deep",
        }
    }

    /// Parses [`Phase::as_str`].
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "free" => Some(Phase::Free),
            "grazing" => Some(Phase::Grazing),
            "deep" => Some(Phase::Deep),
            _ => None,
        }
    }
}

/// One sample of the path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectorySample {
    /// Time since the start, seconds.
    pub time_s: f64,
    /// World pose of the tool (metres); the bunny stays at [`Pose::IDENTITY`].
    pub tool: Pose,
    /// Scripted phase.
    pub phase: Phase,
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Scripted distance of the tool centre beyond the surface (metres) and phase at time `t` (seconds).
fn offset(t: f32) -> (f32, Phase) {
    const FREE: f32 = 0.03;
    // The gem reaches 3.6-5 mm from its centre, so this keeps 0 to about 2 mm of penetration.
    let graze = 0.0042 + 0.001 * (TAU * t / 1.7).sin();
    let deep = -0.02 - 0.01 * (TAU * t / 3.1).sin();
    let mix = |a: f32, b: f32, s: f32| a + (b - a) * s;
    match t {
        t if t < 5.0 => (FREE, Phase::Free),
        t if t < 7.0 => (mix(FREE, graze, smoothstep(5.0, 7.0, t)), Phase::Grazing),
        t if t < 15.0 => (graze, Phase::Grazing),
        t if t < 17.0 => (mix(graze, deep, smoothstep(15.0, 17.0, t)), Phase::Deep),
        t if t < 25.0 => (deep, Phase::Deep),
        t if t < 27.0 => (mix(deep, graze, smoothstep(25.0, 27.0, t)), Phase::Grazing),
        t if t < 32.0 => (graze, Phase::Grazing),
        _ => (mix(graze, FREE, smoothstep(32.0, 34.0, t)), Phase::Free),
    }
}

/// The 35,000 samples of the path around `bunny` (as given by [`super::load_bunny`]). Deterministic.
///
/// The tool circles the bunny (one turn every 20 s, bobbing up and down), following the surface found by
/// casting rays towards the bunny's centre (low-pass filtered with a 50 ms time constant), at the scripted
/// offset: free space, then grazing, deep interpenetration, grazing again and free space. It tumbles
/// slowly about all three axes.
pub fn trajectory(bunny: &TriMesh) -> Vec<TrajectorySample> {
    use parry3d::query::{Ray, RayCast};
    let mesh = crate::packing::to_parry(bunny);
    let center = bunny.aabb().center();
    let far = bunny.aabb().extents().length() * 2.0;
    let n = (TRAJECTORY_SECONDS * TRAJECTORY_RATE_HZ as f64) as usize;
    let dt = 1.0 / TRAJECTORY_RATE_HZ as f32;
    let alpha = 1.0 - (-dt / 0.05f32).exp();
    let mut filtered: Option<f32> = None;
    let mut last_surface = far * 0.25;
    (0..n)
        .map(|i| {
            let t = i as f32 * dt;
            let (az, el) = (TAU * t / 20.0 + 0.3, 0.5 * (TAU * t / 13.0).sin());
            let dir = Vec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin());
            let origin = center + dir * far;
            let ray = Ray::new(
                parry3d::math::Vector::new(origin.x, origin.y, origin.z),
                parry3d::math::Vector::new(-dir.x, -dir.y, -dir.z),
            );
            if let Some(toi) = mesh.cast_local_ray(&ray, far, true) {
                last_surface = far - toi;
            }
            let s = filtered.map_or(last_surface, |f| f + (last_surface - f) * alpha);
            filtered = Some(s);
            let (off, phase) = offset(t);
            let position = center + dir * (s + off).max(0.0);
            let rotation = Quat::from_euler(EulerRot::YXZ, 0.7 * t, 0.4 * (0.5 * t).sin(), 0.2 * t);
            TrajectorySample {
                time_s: i as f64 / TRAJECTORY_RATE_HZ as f64,
                tool: Pose::new(position, rotation),
                phase,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::uv_sphere_buffers;

    #[test]
    fn the_path_has_35000_samples_in_three_phases_and_is_smooth() {
        let (v, t) = uv_sphere_buffers(0.05, 16, 32);
        let ball = TriMesh::new(v, t).expect("valid");
        let path = trajectory(&ball);
        assert_eq!(path.len(), 35_000);
        assert_eq!(path[0].phase, Phase::Free);
        assert!(path.iter().any(|s| s.phase == Phase::Deep));
        let max_step =
            path.windows(2).map(|w| w[0].tool.translation.distance(w[1].tool.translation)).fold(0.0, f32::max);
        assert!(max_step < 0.001, "no jump above 1 mm per millisecond: {max_step}");
        assert_eq!(path, trajectory(&ball), "deterministic");
    }
}
