//! The Falcon's parallel (delta) mechanism: encoder counts to arm angles, angles to the grip's position
//! and back, and a force at the grip to the three motor commands.
//!
//! You need this module to turn what a Falcon reports into a position and a wanted force into what it
//! takes. Coordinates are the mechanism's: metres, x to the right, y up, z out of the body towards the
//! user (the grip's centre of travel at z ≈ 0.11 m, [`CENTRE_Z_M`]). The geometry and the inverse
//! kinematics are those of the delta mechanism as Stamper described it and the libnifalcon project
//! documented for the Falcon (facts only). The position comes from the angles by Newton's method on the
//! inverse kinematics; the Jacobian is taken from the inverse kinematics by central differences, so
//! position, angles and forces stay consistent with each other whatever the formulas' conventions.

use glam::{DMat3, DVec3, Vec3};

/// Link lengths and offsets of the mechanism, m (a, b, c, d, e, f, r, s in Stamper's notation).
const A: f64 = 0.060;
const B: f64 = 0.1025;
const C: f64 = 0.01443;
const D: f64 = 0.01125;
const E: f64 = 0.01125;
const F: f64 = -0.025;
const R: f64 = 0.0400;
const S: f64 = -0.02309;
/// Where each arm sits round the body, rad (top, right, left).
const PHI: [f64; 3] = [
    std::f64::consts::FRAC_PI_2 + std::f64::consts::PI / 12.0,
    -std::f64::consts::PI / 6.0 + std::f64::consts::PI / 12.0,
    -5.0 * std::f64::consts::PI / 6.0 + std::f64::consts::PI / 12.0,
];
/// Slots on an encoder wheel (four counts each), its shaft's and the arm's drum's diameters, m, and the
/// arm's angle at count zero, degrees.
const WHEEL_SLOTS: f64 = 320.0;
const SHAFT_DIAMETER_M: f64 = 0.01425;
const DRUM_DIAMETER_M: f64 = 0.110;
const ANGLE_AT_ZERO_DEG: f64 = 35.0;
/// Largest motor torque asked for before all three are scaled down together (firmware units / 10,000).
const MAX_TORQUE: f64 = 30.0;
/// Motor command per unit of torque.
const COMMAND_PER_TORQUE: f64 = 10_000.0;

/// Depth of the grip's centre of travel, m: the device frame's origin is here.
pub const CENTRE_Z_M: f32 = 0.11;

/// Degrees of arm rotation per encoder count (the shaft turns the drum: about 0.0364°).
pub fn degrees_per_count() -> f64 {
    (SHAFT_DIAMETER_M * std::f64::consts::PI / (WHEEL_SLOTS * 4.0)) / (std::f64::consts::PI * DRUM_DIAMETER_M / 360.0)
}

/// The three arms' angles (rad) for encoder counts.
pub fn angles(encoders: [i16; 3]) -> [f64; 3] {
    encoders.map(|e| (f64::from(e) * degrees_per_count() + ANGLE_AT_ZERO_DEG).to_radians())
}

/// The encoder counts nearest to arm angles (rad); None when one is beyond the counter's range.
pub fn encoders(angles: [f64; 3]) -> Option<[i16; 3]> {
    let mut out = [0i16; 3];
    for (o, a) in out.iter_mut().zip(angles) {
        let counts = ((a.to_degrees() - ANGLE_AT_ZERO_DEG) / degrees_per_count()).round();
        if !(f64::from(i16::MIN)..=f64::from(i16::MAX)).contains(&counts) {
            return None;
        }
        *o = counts as i16;
    }
    Some(out)
}

/// The upper arms' angles (rad) that put the grip at `p` (mechanism frame); None out of reach.
pub fn inverse(p: DVec3) -> Option<[f64; 3]> {
    let mut out = [0.0; 3];
    for (theta, phi) in out.iter_mut().zip(PHI) {
        let (sin, cos) = phi.sin_cos();
        let u = cos * p.x + sin * p.y - R;
        let v = -sin * p.x + cos * p.y - S;
        let w = p.z;
        let theta3 = ((v + F) / B).acos();
        let s3 = theta3.sin();
        let k = w * w + u * u + 2.0 * C * u + A * A + C * C
            - D * D
            - E * E
            - B * B * s3 * s3
            - 2.0 * B * s3 * (D + E)
            - 2.0 * D * E;
        let l0 = k - 2.0 * A * u - 2.0 * A * C;
        let l1 = -4.0 * A * w;
        let l2 = k + 2.0 * A * u + 2.0 * A * C;
        *theta = 2.0 * ((-l1 - (l1 * l1 - 4.0 * l0 * l2).sqrt()) / (2.0 * l2)).atan();
        if !theta.is_finite() {
            return None;
        }
    }
    Some(out)
}

/// ∂θᵢ/∂pⱼ at `p`: how each arm's angle changes as the grip moves (central differences, 1 µm).
pub fn jacobian(p: DVec3) -> Option<DMat3> {
    const H: f64 = 1e-6;
    let mut columns = [DVec3::ZERO; 3];
    for (j, column) in columns.iter_mut().enumerate() {
        let step = DVec3::AXES[j] * H;
        let (plus, minus) = (inverse(p + step)?, inverse(p - step)?);
        *column = (DVec3::from_array(plus) - DVec3::from_array(minus)) / (2.0 * H);
    }
    let m = DMat3::from_cols(columns[0], columns[1], columns[2]);
    (m.determinant().abs() > 1e-12).then_some(m)
}

/// The grip's position (mechanism frame) for arm angles (rad), by Newton's method from `guess`
/// (last tick's position, or [`centre`]): at most 20 steps, to 1e-9 rad. None when it does not
/// converge (a reading no pose gives).
pub fn forward(angles: [f64; 3], guess: DVec3) -> Option<DVec3> {
    let target = DVec3::from_array(angles);
    let mut p = guess;
    for _ in 0..20 {
        let error = target - DVec3::from_array(inverse(p)?);
        if error.abs().max_element() < 1e-9 {
            return Some(p);
        }
        let step = jacobian(p)?.inverse() * error;
        p += step.clamp_length_max(0.02);
    }
    let error = target - DVec3::from_array(inverse(p)?);
    (error.abs().max_element() < 1e-6).then_some(p)
}

/// The centre of travel (mechanism frame).
pub fn centre() -> DVec3 {
    DVec3::new(0.0, 0.0, f64::from(CENTRE_Z_M))
}

/// The motor commands that push the grip at `p` (mechanism frame) with `force` (N, mechanism axes):
/// torques τ = (∂p/∂θ)ᵀ F by virtual work, scaled down together past the firmware's largest, then to
/// command units and clamped to 16 bits. All zero where the Jacobian is singular.
pub fn motor_commands(force: Vec3, p: DVec3) -> [i16; 3] {
    let Some(j) = jacobian(p) else { return [0; 3] };
    let torque = j.inverse().transpose() * force.as_dvec3();
    let largest = torque.abs().max_element();
    let torque = if largest > MAX_TORQUE { torque * (MAX_TORQUE / largest) } else { torque };
    (-torque * COMMAND_PER_TORQUE).to_array().map(|c| c.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_encoder_count_turns_the_arm_about_a_thirtieth_of_a_degree() {
        assert!((degrees_per_count() - 0.0364347).abs() < 1e-6, "{}", degrees_per_count());
        assert_eq!(encoders(angles([-516, 0, 336])), Some([-516, 0, 336]));
    }

    #[test]
    fn at_the_centre_of_travel_all_three_arms_stand_at_the_same_angle() {
        // Known pairs (worked out by hand from the mechanism's equations): at (0, 0, 0.11) every arm is at
        // 16.19°, about −516 counts; at (0, 0, 0.15), 47.24°, about +336 counts.
        for (z, degrees, counts) in [(0.11, 16.188, -516), (0.15, 47.243, 336)] {
            let a = inverse(DVec3::new(0.0, 0.0, z)).expect("in reach");
            for theta in a {
                assert!((theta.to_degrees() - degrees).abs() < 0.01, "z {z}: {}°", theta.to_degrees());
            }
            assert_eq!(encoders(a), Some([counts; 3]), "z {z}");
        }
        let side = encoders(inverse(DVec3::new(0.02, 0.0, 0.11)).expect("in reach")).expect("counts");
        for (got, want) in side.iter().zip([-351, -856, -210]) {
            assert!((got - want).abs() <= 1, "20 mm right: {side:?}");
        }
    }

    #[test]
    fn forward_kinematics_finds_the_position_the_inverse_was_given() {
        for p in [
            DVec3::new(0.0, 0.0, 0.11),
            DVec3::new(0.03, -0.02, 0.09),
            DVec3::new(-0.04, 0.03, 0.14),
            DVec3::new(0.01, 0.04, 0.16),
        ] {
            let a = inverse(p).expect("in reach");
            let found = forward(a, centre()).expect("converges");
            assert!((found - p).length() < 1e-7, "{p} → {found}");
        }
    }

    #[test]
    fn positions_read_from_encoder_counts_are_within_a_tenth_of_a_millimetre() {
        // Counts are whole: the round trip through them loses less than the encoders resolve.
        let p = DVec3::new(0.025, 0.01, 0.12);
        let counts = encoders(inverse(p).expect("in reach")).expect("counts");
        let found = forward(angles(counts), centre()).expect("converges");
        assert!((found - p).length() < 1e-4, "{p} → {found}");
    }

    #[test]
    fn the_motor_torques_do_the_work_of_the_force_on_the_grip() {
        // Virtual work: for a small move dp (dθ = J dp), τ · dθ = F · dp.
        let p = DVec3::new(0.01, -0.015, 0.12);
        let force = Vec3::new(1.0, -2.0, 0.5);
        let j = jacobian(p).expect("regular");
        let torque = -DVec3::from_array(motor_commands(force, p).map(f64::from)) / COMMAND_PER_TORQUE;
        for dp in [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.3, -0.5, 0.8)] {
            let work = torque.dot(j * dp);
            assert!((work - force.as_dvec3().dot(dp)).abs() < 2e-3, "{dp}: {work}");
        }
    }

    #[test]
    fn commands_stay_in_sixteen_bits_and_an_unreachable_pose_gives_none() {
        // A huge force saturates: the largest command sits at the 16-bit limit, none beyond it.
        let saturated = motor_commands(Vec3::splat(1e6), centre());
        assert!(saturated.iter().any(|c| *c == i16::MAX || *c == i16::MIN), "{saturated:?}");
        assert_eq!(motor_commands(Vec3::X, DVec3::new(1.0, 0.0, 0.0)), [0; 3]);
        assert_eq!(inverse(DVec3::new(1.0, 0.0, 0.0)), None);
        assert_eq!(forward([10.0, 10.0, 10.0], centre()), None);
    }
}
