//! Recording device states to a file and replaying them as a device.
//!
//! You need this module to capture a session with a real device once and replay it in tests and
//! benchmarks, or to feed a recorded trajectory through the haptic loop.
//!
//! # Format (`haptico trace v1`)
//! A UTF-8 text file. The first line is exactly `# haptico trace v1`. Other lines starting with `#` and
//! blank lines are ignored. Every other line is one sample of 15 fields separated by single spaces:
//!
//! `t_us px py pz qx qy qz qw vx vy vz wx wy wz buttons`
//!
//! `t_us` is the sample time in microseconds (non-decreasing), `p*` the position in metres, `q*` the unit
//! orientation quaternion, `v*` the linear velocity in m/s, `w*` the angular velocity in rad/s and
//! `buttons` the button bit set as a decimal integer. Floats are written with Rust's shortest round-trip
//! formatting, so a record/replay round trip is exact.

use std::io::{BufRead, BufWriter, Write};
use std::path::Path;

use glam::{Quat, Vec3};
use haptic_common::{Buttons, DeviceState, ForceTorque, Pose};

use crate::{Device, DeviceSpecs, HapticoError, Result};

/// First line of every trace file.
pub const HEADER: &str = "# haptico trace v1";

/// Collects device states with a capacity fixed up front (records nothing past it, never allocates).
#[derive(Clone, Debug)]
pub struct TraceRecorder {
    samples: Vec<DeviceState>,
    dropped: u64,
}

impl TraceRecorder {
    /// A recorder with room for `capacity` samples (allocates once, here).
    pub fn with_capacity(capacity: usize) -> Self {
        Self { samples: Vec::with_capacity(capacity), dropped: 0 }
    }

    /// Records one sample; returns false (and counts it) when full. Allocation-free.
    #[inline]
    pub fn record(&mut self, state: &DeviceState) -> bool {
        if self.samples.len() == self.samples.capacity() {
            self.dropped += 1;
            return false;
        }
        self.samples.push(*state);
        true
    }

    /// The samples recorded.
    pub fn samples(&self) -> &[DeviceState] {
        &self.samples
    }

    /// Samples refused because the recorder was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Writes the samples to `path` in the documented format.
    pub fn save(&self, path: &Path) -> Result<()> {
        save(path, &self.samples)
    }
}

/// Writes `samples` in the trace format to `out`.
pub fn write(out: &mut impl Write, samples: &[DeviceState]) -> std::io::Result<()> {
    writeln!(out, "{HEADER}")?;
    writeln!(out, "# t_us px py pz qx qy qz qw vx vy vz wx wy wz buttons")?;
    for s in samples {
        let (p, q, v, w) = (s.pose.translation, s.pose.rotation, s.linear_velocity, s.angular_velocity);
        writeln!(
            out,
            "{} {} {} {} {} {} {} {} {} {} {} {} {} {} {}",
            s.timestamp_us, p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z, s.buttons.0
        )?;
    }
    Ok(())
}

/// Writes `samples` to the file at `path`.
pub fn save(path: &Path, samples: &[DeviceState]) -> Result<()> {
    let io = |source| HapticoError::Io { path: path.to_owned(), source };
    let mut out = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    write(&mut out, samples).map_err(io)?;
    out.flush().map_err(io)
}

/// Parses a trace from `input`.
pub fn read(input: impl BufRead) -> Result<Vec<DeviceState>> {
    let mut samples = Vec::new();
    let mut last_t = 0u64;
    for (i, line) in input.lines().enumerate() {
        let line_no = i + 1;
        let line = line.map_err(|e| HapticoError::TraceFormat { line: line_no, reason: e.to_string() })?;
        if i == 0 {
            if line.trim_end() != HEADER {
                return Err(HapticoError::TraceFormat { line: 1, reason: format!("expected `{HEADER}`") });
            }
            continue;
        }
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |reason: String| HapticoError::TraceFormat { line: line_no, reason };
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        if fields.len() != 15 {
            return Err(bad(format!("expected 15 fields, found {}", fields.len())));
        }
        let t_us: u64 = fields[0].parse().map_err(|e| bad(format!("t_us: {e}")))?;
        if t_us < last_t {
            return Err(bad("time goes backwards".into()));
        }
        last_t = t_us;
        let mut f = [0f32; 13];
        for (k, slot) in f.iter_mut().enumerate() {
            *slot = fields[k + 1].parse().map_err(|e| bad(format!("field {}: {e}", k + 2)))?;
        }
        let buttons: u32 = fields[14].parse().map_err(|e| bad(format!("buttons: {e}")))?;
        samples.push(DeviceState {
            pose: Pose::new(Vec3::new(f[0], f[1], f[2]), Quat::from_xyzw(f[3], f[4], f[5], f[6])),
            linear_velocity: Vec3::new(f[7], f[8], f[9]),
            angular_velocity: Vec3::new(f[10], f[11], f[12]),
            buttons: Buttons(buttons),
            timestamp_us: t_us,
        });
    }
    Ok(samples)
}

/// Reads the trace file at `path`.
pub fn load(path: &Path) -> Result<Vec<DeviceState>> {
    let file = std::fs::File::open(path).map_err(|source| HapticoError::Io { path: path.to_owned(), source })?;
    read(std::io::BufReader::new(file))
}

/// A device that replays a trace in real time (by the haptic clock) and ignores forces.
#[derive(Clone, Debug)]
pub struct TraceDevice {
    specs: DeviceSpecs,
    samples: Vec<DeviceState>,
    index: usize,
    offset_us: Option<u64>,
    looping: bool,
    last_command: ForceTorque,
}

impl TraceDevice {
    /// A replay of `samples` posing as a device with `specs`; `looping` restarts it at the end.
    pub fn new(specs: DeviceSpecs, samples: Vec<DeviceState>, looping: bool) -> Result<Self> {
        if samples.is_empty() {
            return Err(HapticoError::EmptyTrace);
        }
        Ok(Self { specs, samples, index: 0, offset_us: None, looping, last_command: ForceTorque::ZERO })
    }

    /// True once a non-looping replay has reached its last sample.
    pub fn finished(&self) -> bool {
        !self.looping && self.index + 1 == self.samples.len()
    }

    /// The last force commanded (a trace cannot render it).
    pub fn last_command(&self) -> ForceTorque {
        self.last_command
    }

    fn duration_us(&self) -> u64 {
        let first = self.samples[0].timestamp_us;
        self.samples[self.samples.len() - 1].timestamp_us - first + 1
    }
}

impl Device for TraceDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        let first = self.samples[0].timestamp_us;
        let offset = *self.offset_us.get_or_insert(t_us);
        let mut local = t_us.saturating_sub(offset);
        if self.looping {
            local %= self.duration_us();
            if self.samples[self.index].timestamp_us - first > local {
                self.index = 0;
            }
        }
        while self.index + 1 < self.samples.len() && self.samples[self.index + 1].timestamp_us - first <= local {
            self.index += 1;
        }
        DeviceState { timestamp_us: t_us, ..self.samples[self.index] }
    }

    fn command(&mut self, ft: ForceTorque) {
        self.last_command = ft;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets;

    fn samples() -> Vec<DeviceState> {
        (0..50u64)
            .map(|i| DeviceState {
                pose: Pose::new(
                    Vec3::new(i as f32 * 1e-3, -0.1 / 3.0, 1e-7 * i as f32),
                    Quat::from_rotation_y(i as f32 * 0.01),
                ),
                linear_velocity: Vec3::new(1.0 / 7.0, 0.0, -2.5),
                angular_velocity: Vec3::new(0.0, 0.01, f32::MIN_POSITIVE),
                buttons: Buttons(i as u32 % 3),
                timestamp_us: i * 1000,
            })
            .collect()
    }

    #[test]
    fn a_recorded_trace_reads_back_exactly() {
        let mut rec = TraceRecorder::with_capacity(100);
        for s in samples() {
            assert!(rec.record(&s));
        }
        let dir = std::env::temp_dir().join(format!("haptico-trace-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("round_trip.trace");
        rec.save(&path).expect("save");
        let back = load(&path).expect("load");
        assert_eq!(back, samples());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_recorder_refuses_samples_past_its_capacity() {
        let mut rec = TraceRecorder::with_capacity(3);
        for s in samples() {
            rec.record(&s);
        }
        assert_eq!(rec.samples().len(), 3);
        assert_eq!(rec.dropped(), 47);
    }

    #[test]
    fn malformed_lines_are_reported_with_their_number() {
        let text = format!("{HEADER}\n0 0 0 0 0 0 0 1 0 0 0 0 0 0 0\n5 1 2\n");
        match read(text.as_bytes()) {
            Err(HapticoError::TraceFormat { line, .. }) => assert_eq!(line, 3),
            other => panic!("expected a format error, got {other:?}"),
        }
        assert!(read("not a trace\n".as_bytes()).is_err());
    }

    #[test]
    fn replay_follows_the_recorded_timing() {
        let mut dev = TraceDevice::new(presets::touch(), samples(), false).expect("trace");
        assert_eq!(dev.read_state(10_000).pose, samples()[0].pose);
        assert_eq!(dev.read_state(10_000 + 5_500).pose, samples()[5].pose);
        assert_eq!(dev.read_state(10_000 + 999_000).pose, samples()[49].pose);
        assert!(dev.finished());
    }

    #[test]
    fn a_looping_replay_starts_over() {
        let mut dev = TraceDevice::new(presets::touch(), samples(), true).expect("trace");
        dev.read_state(0);
        assert_eq!(dev.read_state(49_000).pose, samples()[49].pose);
        assert_eq!(dev.read_state(50_000 + 2_000).pose, samples()[2].pose);
    }
}
