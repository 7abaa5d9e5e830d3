//! Device traces: the documented file format, recording a running device to a file, and replaying a
//! trace as a device.
//!
//! You need this module to capture a session (a player's, a benchmark's) once and replay it into a bug
//! report, a test or a benchmark: wrap the device with [`record`] and the haptic thread's every tick —
//! the state read and the force commanded — streams to a file; [`load_trace`] reads it back and
//! [`TraceDevice`] replays it.
//!
//! # Format (`haptico trace v2`)
//! A UTF-8 text file. The first line is exactly `# haptico trace v2` (or `# haptico trace v1`, read the
//! same way without the command). Other lines starting with `#` and blank lines are ignored. Every other
//! line is one tick of 21 fields (v1: the first 15) separated by single spaces:
//!
//! `t_us px py pz qx qy qz qw vx vy vz wx wy wz buttons fx fy fz tx ty tz`
//!
//! `t_us` is the sample time in microseconds (non-decreasing), `p*` the position in metres, `q*` the unit
//! orientation quaternion, `v*` the linear velocity in m/s, `w*` the angular velocity in rad/s,
//! `buttons` the button bit set as a decimal integer, and `f*`/`t*` the force (N) and torque (N·m)
//! commanded on that tick after the state was read. Floats are written with Rust's shortest round-trip
//! formatting, so a record/replay round trip is exact.

mod record;

use std::io::{BufRead, BufWriter, Write};
use std::path::Path;

use glam::{Quat, Vec3};
use haptic_common::{Buttons, DeviceState, ForceTorque, Pose};

use crate::{Device, DeviceSpecs, HapticoError, Result};
pub use record::{Recording, TraceStats, TraceWriter, record};

/// First line of every trace file written now.
pub const HEADER: &str = "# haptico trace v2";
/// First line of a trace of states only (still read).
pub const HEADER_V1: &str = "# haptico trace v1";
/// The column names, written as the second line.
const COLUMNS: &str = "# t_us px py pz qx qy qz qw vx vy vz wx wy wz buttons fx fy fz tx ty tz";

/// A trace read back: the states, and the commands when the file has them (v2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    /// The device state of each tick.
    pub states: Vec<DeviceState>,
    /// The force and torque commanded on each tick (`None` for a v1 file).
    pub commands: Option<Vec<ForceTorque>>,
}

/// Writes the header lines of a v2 trace.
fn write_header(out: &mut impl Write) -> std::io::Result<()> {
    writeln!(out, "{HEADER}")?;
    writeln!(out, "{COLUMNS}")
}

/// Writes one tick as a v2 line.
fn write_tick(out: &mut impl Write, s: &DeviceState, c: &ForceTorque) -> std::io::Result<()> {
    let (p, q, v, w) = (s.pose.translation, s.pose.rotation, s.linear_velocity, s.angular_velocity);
    let (f, t) = (c.force, c.torque);
    writeln!(
        out,
        "{} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {} {}",
        s.timestamp_us,
        p.x,
        p.y,
        p.z,
        q.x,
        q.y,
        q.z,
        q.w,
        v.x,
        v.y,
        v.z,
        w.x,
        w.y,
        w.z,
        s.buttons.0,
        f.x,
        f.y,
        f.z,
        t.x,
        t.y,
        t.z
    )
}

/// Writes `states` and the `commands` of the same ticks as a v2 trace to `out`.
pub fn write(out: &mut impl Write, states: &[DeviceState], commands: &[ForceTorque]) -> std::io::Result<()> {
    if states.len() != commands.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} states but {} commands", states.len(), commands.len()),
        ));
    }
    write_header(out)?;
    for (s, c) in states.iter().zip(commands) {
        write_tick(out, s, c)?;
    }
    Ok(())
}

/// Writes `states` and `commands` to the file at `path`.
pub fn save(path: &Path, states: &[DeviceState], commands: &[ForceTorque]) -> Result<()> {
    let io = |source| HapticoError::Io { path: path.to_owned(), source };
    let mut out = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    write(&mut out, states, commands).map_err(io)?;
    out.flush().map_err(io)
}

/// Parses a trace (v1 or v2) from `input`.
pub fn read_trace(input: impl BufRead) -> Result<Trace> {
    let mut trace = Trace::default();
    let mut commands = Vec::new();
    let mut fields_per_line = 0;
    let mut last_t = 0u64;
    for (i, line) in input.lines().enumerate() {
        let line_no = i + 1;
        let line = line.map_err(|e| HapticoError::TraceFormat { line: line_no, reason: e.to_string() })?;
        if i == 0 {
            fields_per_line = match line.trim_end() {
                HEADER => 21,
                HEADER_V1 => 15,
                _ => {
                    return Err(HapticoError::TraceFormat {
                        line: 1,
                        reason: format!("expected `{HEADER}` or `{HEADER_V1}`"),
                    });
                }
            };
            continue;
        }
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |reason: String| HapticoError::TraceFormat { line: line_no, reason };
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        if fields.len() != fields_per_line {
            return Err(bad(format!("expected {fields_per_line} fields, found {}", fields.len())));
        }
        let t_us: u64 = fields[0].parse().map_err(|e| bad(format!("t_us: {e}")))?;
        if t_us < last_t {
            return Err(bad("time goes backwards".into()));
        }
        last_t = t_us;
        let float = |k: usize| -> Result<f32> { fields[k].parse().map_err(|e| bad(format!("field {}: {e}", k + 1))) };
        let mut f = [0f32; 13];
        for (k, slot) in f.iter_mut().enumerate() {
            *slot = float(k + 1)?;
        }
        let buttons: u32 = fields[14].parse().map_err(|e| bad(format!("buttons: {e}")))?;
        trace.states.push(DeviceState {
            pose: Pose::new(Vec3::new(f[0], f[1], f[2]), Quat::from_xyzw(f[3], f[4], f[5], f[6])),
            linear_velocity: Vec3::new(f[7], f[8], f[9]),
            angular_velocity: Vec3::new(f[10], f[11], f[12]),
            buttons: Buttons(buttons),
            timestamp_us: t_us,
        });
        if fields_per_line == 21 {
            commands.push(ForceTorque {
                force: Vec3::new(float(15)?, float(16)?, float(17)?),
                torque: Vec3::new(float(18)?, float(19)?, float(20)?),
            });
        }
    }
    if fields_per_line == 21 {
        trace.commands = Some(commands);
    }
    Ok(trace)
}

/// Parses the states of a trace (v1 or v2) from `input`.
pub fn read(input: impl BufRead) -> Result<Vec<DeviceState>> {
    read_trace(input).map(|t| t.states)
}

/// Reads the trace file at `path`.
pub fn load_trace(path: &Path) -> Result<Trace> {
    let file = std::fs::File::open(path).map_err(|source| HapticoError::Io { path: path.to_owned(), source })?;
    read_trace(std::io::BufReader::new(file))
}

/// Reads the states of the trace file at `path`.
pub fn load(path: &Path) -> Result<Vec<DeviceState>> {
    load_trace(path).map(|t| t.states)
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

    fn commands() -> Vec<ForceTorque> {
        (0..50u64)
            .map(|i| ForceTorque {
                force: Vec3::new(0.1 * i as f32, -1.0 / 3.0, f32::MIN_POSITIVE),
                torque: Vec3::new(0.0, 1e-9 * i as f32, -0.0),
            })
            .collect()
    }

    #[test]
    fn a_saved_trace_reads_back_exactly() {
        let dir = std::env::temp_dir().join(format!("haptico-trace-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("round_trip.trace");
        save(&path, &samples(), &commands()).expect("save");
        let back = load_trace(&path).expect("load");
        assert_eq!(back.states, samples());
        let bits = |c: &[ForceTorque]| c.iter().map(ForceTorque::to_bits).collect::<Vec<_>>();
        assert_eq!(back.commands.as_deref(), Some(&commands()[..]));
        assert_eq!(bits(back.commands.as_deref().unwrap_or_default()), bits(&commands()), "to the bit, -0.0 too");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_v1_trace_of_states_only_still_reads() {
        let text = format!("{HEADER_V1}\n# comment\n\n7 0 0 0 0 0 0 1 0 0 0 0 0 0 2\n");
        let trace = read_trace(text.as_bytes()).expect("v1");
        assert_eq!(trace.states.len(), 1);
        assert_eq!(trace.states[0].timestamp_us, 7);
        assert_eq!(trace.states[0].buttons, Buttons(2));
        assert_eq!(trace.commands, None);
    }

    #[test]
    fn states_and_commands_of_different_lengths_are_refused() {
        let mut out = Vec::new();
        assert!(write(&mut out, &samples(), &commands()[..3]).is_err());
    }

    #[test]
    fn malformed_lines_are_reported_with_their_number() {
        let text = format!("{HEADER_V1}\n0 0 0 0 0 0 0 1 0 0 0 0 0 0 0\n5 1 2\n");
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
