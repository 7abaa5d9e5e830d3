//! A simulated device: the end effector and the user's hand as one mass-spring-damper pulled along a
//! target path, with encoder quantization, filtered velocity and optional timing jitter.
//!
//! You need this module to run the haptic loop without hardware (tests, benchmarks, CI). Because the hand
//! is a spring following its path, an unstable force law shows up as sustained oscillation, as on a real
//! device.

use glam::{Quat, Vec3};
use haptic_common::{DeviceState, ForceTorque, Pose};

use crate::{Device, DeviceSpecs};

/// The user's hand holding the stylus, as seen by the device (second-order impedance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandModel {
    /// Moving mass of hand plus end effector, kg (default 0.15).
    pub mass_kg: f32,
    /// Grip stiffness towards the target path, N/m (default 200).
    pub stiffness_n_per_m: f32,
    /// Grip damping, N·s/m (default 4).
    pub damping_ns_per_m: f32,
    /// Rotational inertia, kg·m² (default 2e-4).
    pub inertia_kg_m2: f32,
    /// Rotational grip stiffness, N·m/rad (default 0.3).
    pub rot_stiffness_nm_per_rad: f32,
    /// Rotational grip damping, N·m·s/rad (default 0.005).
    pub rot_damping_nms_per_rad: f32,
}

impl Default for HandModel {
    fn default() -> Self {
        Self {
            mass_kg: 0.15,
            stiffness_n_per_m: 200.0,
            damping_ns_per_m: 4.0,
            inertia_kg_m2: 2e-4,
            rot_stiffness_nm_per_rad: 0.3,
            rot_damping_nms_per_rad: 0.005,
        }
    }
}

/// One pose of a [`TargetPath`] at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Time since the start of the path, s.
    pub t_s: f64,
    /// Where the hand wants the end effector, device frame.
    pub pose: Pose,
}

/// Where the hand wants to be over time.
#[derive(Clone, Debug, PartialEq)]
pub enum TargetPath {
    /// Stay at one pose.
    Hold(Pose),
    /// Interpolate between keyframes sorted by time (hold the first before it, the last after it).
    Keyframes(Vec<Keyframe>),
}

impl TargetPath {
    /// A straight line from `from` to `to` in `duration_s`, then hold.
    pub fn line(from: Vec3, to: Vec3, duration_s: f64) -> Self {
        Self::Keyframes(vec![
            Keyframe { t_s: 0.0, pose: Pose::from_translation(from) },
            Keyframe { t_s: duration_s, pose: Pose::from_translation(to) },
        ])
    }

    /// Target pose and linear velocity (m/s) at `t_s`. Does not allocate.
    pub fn sample(&self, t_s: f64) -> (Pose, Vec3) {
        match self {
            Self::Hold(p) => (*p, Vec3::ZERO),
            Self::Keyframes(k) => {
                let (Some(first), Some(last)) = (k.first(), k.last()) else {
                    return (Pose::IDENTITY, Vec3::ZERO);
                };
                if t_s <= first.t_s {
                    return (first.pose, Vec3::ZERO);
                }
                if t_s >= last.t_s {
                    return (last.pose, Vec3::ZERO);
                }
                let i = k.partition_point(|f| f.t_s <= t_s).clamp(1, k.len() - 1);
                let (a, b) = (&k[i - 1], &k[i]);
                let span = (b.t_s - a.t_s).max(1e-9);
                let s = ((t_s - a.t_s) / span) as f32;
                let pose = Pose::new(
                    a.pose.translation.lerp(b.pose.translation, s),
                    a.pose.rotation.slerp(b.pose.rotation, s),
                );
                (pose, (b.pose.translation - a.pose.translation) / span as f32)
            }
        }
    }
}

/// Settings of a [`SimDevice`].
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    /// The device simulated (limits the force it can exert).
    pub specs: DeviceSpecs,
    /// The hand holding it.
    pub hand: HandModel,
    /// Viscous friction of the mechanism, N·s/m (default 0.1).
    pub mechanism_damping_ns_per_m: f32,
    /// Encoder resolution in position, m (default 2e-5; 0 = exact).
    pub encoder_resolution_m: f32,
    /// Encoder resolution in orientation, rad (default 1e-3; 0 = exact).
    pub encoder_resolution_rad: f32,
    /// Cut-off of the first-order velocity filter, Hz (default 200).
    pub velocity_cutoff_hz: f32,
    /// Largest random extra delay in `read_state`, µs, emulating bus latency (default 0).
    pub jitter_us: u32,
    /// Seed of the jitter generator (default 1).
    pub seed: u64,
    /// Physics sub-step, s (default 1e-4).
    pub substep_s: f32,
}

impl SimConfig {
    /// Default settings for a device with `specs`.
    pub fn new(specs: DeviceSpecs) -> Self {
        Self {
            specs,
            hand: HandModel::default(),
            mechanism_damping_ns_per_m: 0.1,
            encoder_resolution_m: 2e-5,
            encoder_resolution_rad: 1e-3,
            velocity_cutoff_hz: 200.0,
            jitter_us: 0,
            seed: 1,
            substep_s: 1e-4,
        }
    }
}

/// At most this much simulated time is caught up in one read, s (a stalled thread skips the rest).
const MAX_CATCH_UP_S: f64 = 0.02;

/// The simulated device.
#[derive(Clone, Debug)]
pub struct SimDevice {
    config: SimConfig,
    path: TargetPath,
    origin_us: Option<u64>,
    t_s: f64,
    x: Vec3,
    v: Vec3,
    q: Quat,
    w: Vec3,
    cmd: ForceTorque,
    last_read_s: f64,
    last_pos_q: Vec3,
    last_rot_q: Quat,
    vel_f: Vec3,
    ang_vel_f: Vec3,
    rng: u64,
}

impl SimDevice {
    /// A simulated device whose hand follows `path`, starting at rest on the path's first pose.
    pub fn new(config: SimConfig, path: TargetPath) -> Self {
        let (start, _) = path.sample(0.0);
        let rng = config.seed.max(1);
        Self {
            config,
            path,
            origin_us: None,
            t_s: 0.0,
            x: start.translation,
            v: Vec3::ZERO,
            q: start.rotation,
            w: Vec3::ZERO,
            cmd: ForceTorque::ZERO,
            last_read_s: 0.0,
            last_pos_q: start.translation,
            last_rot_q: start.rotation,
            vel_f: Vec3::ZERO,
            ang_vel_f: Vec3::ZERO,
            rng,
        }
    }

    /// The exact (unquantized) position, m.
    pub fn true_position(&self) -> Vec3 {
        self.x
    }

    /// The exact velocity, m/s.
    pub fn true_velocity(&self) -> Vec3 {
        self.v
    }

    /// Simulated time, s.
    pub fn time_s(&self) -> f64 {
        self.t_s
    }

    /// Kinetic energy of the moving mass and rotor, J.
    pub fn kinetic_energy_j(&self) -> f32 {
        let h = &self.config.hand;
        0.5 * h.mass_kg * self.v.length_squared() + 0.5 * h.inertia_kg_m2 * self.w.length_squared()
    }

    /// Replaces the target path (off the haptic thread, or before starting it).
    pub fn set_path(&mut self, path: TargetPath) {
        self.path = path;
    }

    /// Advances the physics by one sub-step of `h` seconds.
    fn step(&mut self, h: f32) {
        let hand = self.config.hand;
        let (target, target_v) = self.path.sample(self.t_s);
        let f = hand.stiffness_n_per_m * (target.translation - self.x) + hand.damping_ns_per_m * (target_v - self.v)
            - self.config.mechanism_damping_ns_per_m * self.v
            + self.cmd.force;
        self.v += f / hand.mass_kg * h;
        self.x += self.v * h;
        let mut err = target.rotation * self.q.inverse();
        if err.w < 0.0 {
            err = -err;
        }
        let tau = hand.rot_stiffness_nm_per_rad * err.to_scaled_axis() - hand.rot_damping_nms_per_rad * self.w
            + self.cmd.torque;
        self.w += tau / hand.inertia_kg_m2 * h;
        self.q = (Quat::from_scaled_axis(self.w * h) * self.q).normalize();
        self.t_s += h as f64;
    }

    fn quantize(&self) -> (Vec3, Quat) {
        let r = self.config.encoder_resolution_m;
        let pos = if r > 0.0 { (self.x / r).round() * r } else { self.x };
        let rr = self.config.encoder_resolution_rad;
        let rot = if rr > 0.0 { Quat::from_scaled_axis((self.q.to_scaled_axis() / rr).round() * rr) } else { self.q };
        (pos, rot)
    }

    fn next_random(&mut self) -> u64 {
        // xorshift64: deterministic, allocation-free.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.rng = x;
        x
    }
}

impl Device for SimDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.config.specs
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        if self.config.jitter_us > 0 {
            let extra = self.next_random() % (self.config.jitter_us as u64 + 1);
            let until = std::time::Instant::now() + std::time::Duration::from_micros(extra);
            while std::time::Instant::now() < until {
                std::hint::spin_loop();
            }
        }
        let origin = *self.origin_us.get_or_insert(t_us);
        let target_s = t_us.saturating_sub(origin) as f64 * 1e-6;
        if target_s - self.t_s > MAX_CATCH_UP_S {
            self.t_s = target_s - MAX_CATCH_UP_S;
        }
        let h = self.config.substep_s.max(1e-6);
        while self.t_s + 0.5 * h as f64 <= target_s {
            self.step(h);
        }
        let (pos, rot) = self.quantize();
        let dt = (target_s - self.last_read_s) as f32;
        if dt > 0.0 {
            let alpha = dt / (dt + 1.0 / (std::f32::consts::TAU * self.config.velocity_cutoff_hz.max(1.0)));
            let raw_v = (pos - self.last_pos_q) / dt;
            let mut dq = rot * self.last_rot_q.inverse();
            if dq.w < 0.0 {
                dq = -dq;
            }
            let raw_w = dq.to_scaled_axis() / dt;
            self.vel_f += alpha * (raw_v - self.vel_f);
            self.ang_vel_f += alpha * (raw_w - self.ang_vel_f);
        }
        self.last_read_s = target_s;
        self.last_pos_q = pos;
        self.last_rot_q = rot;
        DeviceState {
            pose: Pose::new(pos, rot),
            linear_velocity: self.vel_f,
            angular_velocity: self.ang_vel_f,
            buttons: Default::default(),
            timestamp_us: t_us,
        }
    }

    fn command(&mut self, ft: ForceTorque) {
        self.cmd = self.config.specs.clamp(ft);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets;

    fn run(dev: &mut SimDevice, seconds: f64, mut each_tick: impl FnMut(&mut SimDevice, &DeviceState)) {
        let ticks = (seconds * 1000.0) as u64;
        for i in 0..ticks {
            let s = dev.read_state(i * 1000);
            each_tick(dev, &s);
        }
    }

    #[test]
    fn the_hand_brings_the_device_to_a_held_target() {
        let target = Vec3::new(0.01, 0.02, -0.01);
        let mut dev = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::line(Vec3::ZERO, target, 0.5));
        run(&mut dev, 2.0, |_, _| {});
        assert!((dev.true_position() - target).length() < 1e-4, "{:?}", dev.true_position());
        assert!(dev.true_velocity().length() < 1e-3);
    }

    #[test]
    fn a_constant_force_deflects_the_hand_by_force_over_stiffness() {
        let mut dev = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(Pose::IDENTITY));
        dev.command(ForceTorque { force: Vec3::new(1.0, 0.0, 0.0), torque: Vec3::ZERO });
        run(&mut dev, 3.0, |_, _| {});
        // Static equilibrium: k x = F with k = 200 N/m.
        assert!((dev.true_position().x - 1.0 / 200.0).abs() < 1e-4, "{:?}", dev.true_position());
    }

    #[test]
    fn reported_positions_are_quantized_to_the_encoder_resolution() {
        let mut cfg = SimConfig::new(presets::touch());
        cfg.encoder_resolution_m = 1e-3;
        let mut dev = SimDevice::new(cfg, TargetPath::line(Vec3::ZERO, Vec3::new(0.0123, 0.0, 0.0), 0.2));
        run(&mut dev, 1.0, |_, s| {
            let steps = s.pose.translation.x / 1e-3;
            assert!((steps - steps.round()).abs() < 1e-3);
        });
    }

    #[test]
    fn reported_velocity_follows_the_true_velocity_on_a_slow_motion() {
        let mut dev =
            SimDevice::new(SimConfig::new(presets::touch()), TargetPath::line(Vec3::ZERO, Vec3::X * 0.1, 2.0));
        let mut last = DeviceState::default();
        run(&mut dev, 1.0, |_, s| last = *s);
        assert!((last.linear_velocity.x - 0.05).abs() < 0.01, "{:?}", last.linear_velocity);
    }

    #[test]
    fn commands_beyond_the_peak_force_are_limited_by_the_device() {
        let mut dev = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(Pose::IDENTITY));
        dev.command(ForceTorque { force: Vec3::new(100.0, 0.0, 0.0), torque: Vec3::ZERO });
        run(&mut dev, 3.0, |_, _| {});
        assert!((dev.true_position().x - 3.3 / 200.0).abs() < 2e-4);
    }

    #[test]
    fn a_stalled_thread_does_not_make_one_read_simulate_forever() {
        let mut dev = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(Pose::IDENTITY));
        dev.read_state(0);
        dev.read_state(60_000_000);
        assert!((dev.time_s() - 60.0).abs() < 1e-3);
    }
}
