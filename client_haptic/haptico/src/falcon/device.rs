//! A Falcon as a [`Device`]: one packet exchange per tick over a [`Transport`], homing before any
//! force, the position by forward kinematics, the force by the mechanism's Jacobian.
//!
//! You need this module to drive a Falcon from the haptic thread. The transport is a trait so the
//! whole device can be tested against a simulated firmware; the game thread watches homing and faults
//! through a [`FalconStatus`] shared with it (atomics only).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU64, Ordering};

use glam::{DVec3, Vec3};
use haptic_common::{Buttons, DeviceState, ForceTorque, Pose};

use super::homing::Homing;
use super::kinematics::{self, CENTRE_Z_M};
use super::packet::{self, Command, PACKET_LEN, Reply};
use crate::{Device, DeviceSpecs};

/// Why one exchange failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TransportError {
    /// No reply in time.
    #[error("the Falcon did not answer in time")]
    Timeout,
    /// The device is gone (unplugged).
    #[error("the Falcon was disconnected")]
    Disconnected,
}

/// One packet out and its reply back. Called from the haptic thread: must not allocate or block
/// longer than a tick.
pub trait Transport: Send {
    /// Sends `out` and fills `reply` with the Falcon's answer.
    fn exchange(&mut self, out: &[u8; PACKET_LEN], reply: &mut [u8; PACKET_LEN]) -> Result<(), TransportError>;
}

/// What the game thread can read about a running Falcon.
#[derive(Debug, Default)]
pub struct FalconStatus {
    replies: AtomicU64,
    homed: AtomicU8,
    disconnected: AtomicBool,
    bad_packets: AtomicU64,
    failed_exchanges: AtomicU64,
}

impl FalconStatus {
    /// Replies taken so far (the firmware is running once there is one).
    pub fn replies(&self) -> u64 {
        self.replies.load(Ordering::Relaxed)
    }

    /// Which arms are home (top, right, left).
    pub fn homed(&self) -> [bool; 3] {
        let bits = self.homed.load(Ordering::Relaxed);
        [bits & 1 != 0, bits & 2 != 0, bits & 4 != 0]
    }

    /// True once the Falcon reported itself unplugged.
    pub fn disconnected(&self) -> bool {
        self.disconnected.load(Ordering::Relaxed)
    }

    /// Replies refused so far (framing or nibble errors).
    pub fn bad_packets(&self) -> u64 {
        self.bad_packets.load(Ordering::Relaxed)
    }

    /// Exchanges that timed out or failed so far.
    pub fn failed_exchanges(&self) -> u64 {
        self.failed_exchanges.load(Ordering::Relaxed)
    }
}

/// A Falcon whose firmware is running, behind `T`.
pub struct FalconDevice<T: Transport> {
    transport: T,
    specs: DeviceSpecs,
    homing: Homing,
    status: Arc<FalconStatus>,
    command: Command,
    /// Last position found (mechanism frame), the next forward kinematics' starting guess.
    position: DVec3,
    state: DeviceState,
    last_t_us: Option<u64>,
}

impl<T: Transport> FalconDevice<T> {
    /// A Falcon behind `transport` with `specs` (e.g. [`crate::presets::falcon`]), not yet homed.
    pub fn new(transport: T, specs: DeviceSpecs) -> Self {
        Self {
            transport,
            specs,
            homing: Homing::new(),
            status: Arc::new(FalconStatus::default()),
            command: Command::default(),
            position: kinematics::centre(),
            state: DeviceState::default(),
            last_t_us: None,
        }
    }

    /// The status the game thread watches (homing, unplugged, faults).
    pub fn status(&self) -> Arc<FalconStatus> {
        self.status.clone()
    }

    /// The transport (e.g. to load the firmware before the first exchange).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    fn take(&mut self, reply: &Reply, t_us: u64) {
        self.status.replies.fetch_add(1, Ordering::Relaxed);
        self.homing.update(reply, t_us);
        let bits = reply.homed.iter().enumerate().fold(0u8, |b, (i, h)| b | (u8::from(*h) << i));
        self.status.homed.store(bits, Ordering::Relaxed);
        let Some(p) = kinematics::forward(kinematics::angles(reply.encoders), self.position) else { return };
        self.position = p;
        let device = (p - DVec3::new(0.0, 0.0, f64::from(CENTRE_Z_M))).as_vec3();
        let velocity = match self.last_t_us {
            Some(t) if t_us > t => {
                let raw = (device - self.state.pose.translation) / ((t_us - t) as f32 * 1e-6);
                // Encoder steps make raw differences jumpy: a light low-pass (about 100 Hz at 1 kHz).
                self.state.linear_velocity + (raw - self.state.linear_velocity) * 0.5
            }
            _ => Vec3::ZERO,
        };
        self.last_t_us = Some(t_us);
        self.state = DeviceState {
            pose: Pose::from_translation(device),
            linear_velocity: velocity,
            angular_velocity: Vec3::ZERO,
            buttons: Buttons(u32::from(reply.buttons)),
            timestamp_us: t_us,
        };
    }
}

impl<T: Transport> Device for FalconDevice<T> {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    /// Exchanges one packet (the last command, with homing asked for until homed) and reads the reply.
    fn read_state(&mut self, t_us: u64) -> DeviceState {
        self.command.homing = self.homing.request();
        self.command.leds = self.homing.leds();
        if !self.homing.forces_allowed() {
            self.command.motors = [0; 3];
        }
        let mut reply = [0u8; PACKET_LEN];
        match self.transport.exchange(&packet::encode(&self.command), &mut reply) {
            Ok(()) => match packet::decode(&reply) {
                Ok(r) => self.take(&r, t_us),
                Err(_) => {
                    self.status.bad_packets.fetch_add(1, Ordering::Relaxed);
                }
            },
            Err(e) => {
                self.status.failed_exchanges.fetch_add(1, Ordering::Relaxed);
                if e == TransportError::Disconnected {
                    self.status.disconnected.store(true, Ordering::Relaxed);
                }
            }
        }
        // A reply lost keeps the last state (its timestamp tells how old it is).
        self.state
    }

    /// Sets the motor commands for the next exchange (zero until homed).
    fn command(&mut self, ft: ForceTorque) {
        let force = self.specs.clamp(ft).force;
        self.command.motors =
            if self.homing.forces_allowed() { kinematics::motor_commands(force, self.position) } else { [0; 3] };
    }

    fn release(&mut self) {
        self.command.motors = [0; 3];
        let mut reply = [0u8; PACKET_LEN];
        let _ = self.transport.exchange(&packet::encode(&self.command), &mut reply);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets;

    /// A firmware on a grip held at a position: answers each packet with the encoder counts of that
    /// position, homed once asked `home_after` times; records the motor commands it was sent.
    struct Firmware {
        at: DVec3,
        asked: u32,
        home_after: u32,
        sent: Vec<[i16; 3]>,
        unplug_after: Option<usize>,
    }

    impl Transport for Firmware {
        fn exchange(&mut self, out: &[u8; PACKET_LEN], reply: &mut [u8; PACKET_LEN]) -> Result<(), TransportError> {
            if self.unplug_after.is_some_and(|n| self.sent.len() >= n) {
                return Err(TransportError::Disconnected);
            }
            let motors = packet::decode(out).expect("the host sends framed packets").encoders;
            self.sent.push(motors);
            if out[13].wrapping_sub(0x41) & 0x01 != 0 {
                self.asked += 1;
            }
            let counts = kinematics::encoders(kinematics::inverse(self.at).expect("in reach")).expect("counts");
            let mut p = packet::encode(&Command { motors: counts, leds: 0, homing: false });
            let homed = if self.asked >= self.home_after { 0x70 } else { 0x10 };
            p[13] = 0x41 + homed;
            *reply = p;
            Ok(())
        }
    }

    fn falcon(at: DVec3, home_after: u32) -> FalconDevice<Firmware> {
        let sent = Vec::with_capacity(4096);
        FalconDevice::new(Firmware { at, asked: 0, home_after, sent, unplug_after: None }, presets::falcon())
    }

    #[test]
    fn the_grip_is_where_its_encoders_say_relative_to_the_centre_of_travel() {
        let mut f = falcon(DVec3::new(0.02, -0.01, 0.13), 1);
        let s = f.read_state(1000);
        assert!((s.pose.translation - Vec3::new(0.02, -0.01, 0.02)).length() < 1e-4, "{:?}", s.pose);
        assert_eq!(s.timestamp_us, 1000);
    }

    #[test]
    fn no_force_reaches_the_motors_before_every_arm_is_home() {
        let mut f = falcon(kinematics::centre(), 3);
        for t in 0..5u64 {
            f.read_state(t * 1000);
            f.command(ForceTorque { force: Vec3::new(0.0, 2.0, 0.0), torque: Vec3::ZERO });
        }
        // Homed in the reply to the third packet: the force commanded after it goes out in the fourth.
        let sent = &f.transport.sent;
        assert!(sent[..3].iter().all(|m| *m == [0; 3]), "{sent:?}");
        assert!(sent[3] != [0; 3] && sent[4] != [0; 3], "{sent:?}");
        assert_eq!(f.status().homed(), [true; 3]);
    }

    #[test]
    fn an_upward_force_pushes_every_arm_the_same_way_at_the_centre() {
        let mut f = falcon(kinematics::centre(), 0);
        f.read_state(0);
        f.command(ForceTorque { force: Vec3::new(0.0, 0.0, 3.0), torque: Vec3::ZERO });
        f.read_state(1000);
        let m = f.transport.sent[1];
        assert!(m[0] != 0 && m.iter().all(|c| c.signum() == m[0].signum()), "{m:?}");
        assert!((m[0] - m[1]).abs() <= 1 && (m[1] - m[2]).abs() <= 1, "symmetric: {m:?}");
    }

    #[test]
    fn a_tick_of_a_homed_falcon_neither_allocates_nor_frees() {
        let mut f = falcon(DVec3::new(0.01, 0.02, 0.12), 0);
        f.read_state(0);
        assert_no_alloc::assert_no_alloc(|| {
            for t in 1..1000u64 {
                f.read_state(t * 1000);
                f.command(ForceTorque { force: Vec3::new(0.5, -1.0, 2.0), torque: Vec3::ZERO });
            }
        });
        assert!(f.transport.sent[999] != [0; 3]);
    }

    #[test]
    fn unplugged_it_keeps_its_last_state_and_says_so_without_panicking() {
        let mut f = falcon(kinematics::centre(), 0);
        f.transport.unplug_after = Some(2);
        let first = f.read_state(0);
        f.read_state(1000);
        let later = f.read_state(2000);
        assert_eq!(later.pose, first.pose);
        let status = f.status();
        assert!(status.disconnected() && status.failed_exchanges() == 1 && status.replies() == 2);
        f.release();
    }
}
