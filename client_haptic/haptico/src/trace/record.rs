//! Recording a running device: a [`Recording`] wraps the device on the haptic thread and pushes each
//! tick (the state read, the force commanded) into a ring allocated up front; a [`TraceWriter`] thread
//! drains the ring into the trace file. The haptic thread never allocates, locks, blocks or writes: a
//! full ring (the writer fell ~16 s behind) drops ticks and counts them.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use haptic_common::{DeviceState, ForceTorque};

use super::{write_header, write_tick};
use crate::{Device, DeviceSpecs, HapticoError, Result};

/// Ticks the ring holds: 16 s at 1 kHz (the writer drains it every few milliseconds).
const RING_TICKS: usize = 1 << 14;
/// How long the writer sleeps when the ring is empty.
const WRITER_NAP: Duration = Duration::from_millis(5);

/// A device whose every tick is recorded (see [`record`]). Behaves exactly as the device it wraps.
pub struct Recording<D> {
    device: D,
    last_state: DeviceState,
    ticks: rtrb::Producer<(DeviceState, ForceTorque)>,
    recorded: u64,
    dropped: Arc<AtomicU64>,
}

impl<D: std::fmt::Debug> std::fmt::Debug for Recording<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recording").field("device", &self.device).finish_non_exhaustive()
    }
}

impl<D> Recording<D> {
    /// The device recorded.
    pub fn inner(&self) -> &D {
        &self.device
    }

    /// Ticks recorded so far (written or lost).
    pub fn ticks(&self) -> u64 {
        self.recorded
    }

    /// The device recorded, mutably.
    pub fn inner_mut(&mut self) -> &mut D {
        &mut self.device
    }
}

impl<D: Device> Device for Recording<D> {
    fn specs(&self) -> &DeviceSpecs {
        self.device.specs()
    }

    fn read_state(&mut self, t_us: u64) -> DeviceState {
        self.last_state = self.device.read_state(t_us);
        self.last_state
    }

    /// Commands the device, then records the tick (state read, force commanded). Allocation-free.
    fn command(&mut self, ft: ForceTorque) {
        self.device.command(ft);
        self.recorded += 1;
        if self.ticks.push((self.last_state, ft)).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn release(&mut self) {
        self.device.release();
    }
}

/// What a recording wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Ticks written to the file.
    pub written: u64,
    /// Ticks lost because the ring was full (the writer could not keep up).
    pub dropped: u64,
}

/// The thread that writes a recording's ticks to its file.
#[derive(Debug)]
pub struct TraceWriter {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    dropped: Arc<AtomicU64>,
    join: Option<JoinHandle<std::io::Result<u64>>>,
}

/// Starts recording `device` into a new trace file at `path` (created now, so a bad path fails here):
/// use the returned [`Recording`] as the device, and call [`TraceWriter::finish`] once the haptic thread
/// has stopped.
pub fn record<D: Device>(device: D, path: &Path) -> Result<(Recording<D>, TraceWriter)> {
    let io = |source| HapticoError::Io { path: path.to_owned(), source };
    let mut out = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    write_header(&mut out).map_err(io)?;
    let (tx, mut rx) = rtrb::RingBuffer::<(DeviceState, ForceTorque)>::new(RING_TICKS);
    let stop = Arc::new(AtomicBool::new(false));
    let dropped = Arc::new(AtomicU64::new(0));
    let stop_writer = stop.clone();
    let join = std::thread::Builder::new()
        .name("trace-writer".into())
        .spawn(move || -> std::io::Result<u64> {
            let mut written = 0u64;
            loop {
                // Read the flags before draining, so that nothing pushed before they were set is left.
                let done = stop_writer.load(Ordering::Acquire) || rx.is_abandoned();
                let mut any = false;
                while let Ok((state, command)) = rx.pop() {
                    write_tick(&mut out, &state, &command)?;
                    written += 1;
                    any = true;
                }
                if done {
                    out.flush()?;
                    return Ok(written);
                }
                if !any {
                    std::thread::sleep(WRITER_NAP);
                }
            }
        })
        .map_err(io)?;
    let recording =
        Recording { device, last_state: DeviceState::default(), ticks: tx, recorded: 0, dropped: dropped.clone() };
    Ok((recording, TraceWriter { path: path.to_owned(), stop, dropped, join: Some(join) }))
}

impl TraceWriter {
    /// The file written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Ticks lost so far because the ring was full.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Writes what is left in the ring, closes the file and says what was written. Call it after the
    /// haptic thread stopped (ticks recorded later are not written).
    pub fn finish(mut self) -> Result<TraceStats> {
        self.finish_inner()
    }

    fn finish_inner(&mut self) -> Result<TraceStats> {
        let Some(join) = self.join.take() else { return Ok(TraceStats::default()) };
        self.stop.store(true, Ordering::Release);
        let io = |source| HapticoError::Io { path: self.path.clone(), source };
        let written = join.join().map_err(|_| io(std::io::Error::other("the trace writer panicked")))?.map_err(io)?;
        Ok(TraceStats { written, dropped: self.dropped() })
    }
}

impl Drop for TraceWriter {
    fn drop(&mut self) {
        let _ = self.finish_inner();
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::sim::{SimConfig, SimDevice, TargetPath};
    use crate::trace::load_trace;
    use crate::{HapticCore, HapticEvents, presets};

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("haptico-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join(name)
    }

    fn floor_events() -> HapticEvents {
        let mut events = HapticEvents::with_capacity(2);
        events.force_on_haptic_tick.add_delegate(|t: &haptic_common::ForceOnHapticTick| {
            let y = t.device.pose.translation.y;
            if y < 0.0 {
                t.add(ForceTorque { force: Vec3::Y * (-400.0 * y), torque: Vec3::ZERO });
            }
        });
        events
    }

    #[test]
    fn every_tick_is_written_with_the_state_read_and_the_force_commanded() {
        let path = temp("ticks.trace");
        let device = SimDevice::new(
            SimConfig::new(presets::touch()),
            TargetPath::line(Vec3::new(0.0, 0.01, 0.0), Vec3::new(0.0, -0.01, 0.0), 0.5),
        );
        let (device, writer) = record(device, &path).expect("record");
        let mut core = HapticCore::new(device, floor_events(), 1000.0);
        let (mut states, mut commands) = (Vec::new(), Vec::new());
        for i in 0..800u64 {
            let command = core.tick(i * 1000);
            states.push(core.last_state());
            commands.push(command);
        }
        drop(core);
        let stats = writer.finish().expect("finish");
        assert_eq!(stats, TraceStats { written: 800, dropped: 0 });
        let trace = load_trace(&path).expect("load");
        assert_eq!(trace.states, states);
        assert_eq!(trace.commands.as_deref(), Some(&commands[..]));
        assert!(commands.iter().any(|c| c.force.y > 1.0), "the path goes into the floor and is pushed back");
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn a_recorded_tick_neither_allocates_nor_blocks_and_a_full_ring_counts_what_it_drops() {
        let path = temp("full.trace");
        let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(haptic_common::Pose::IDENTITY));
        let (mut device, writer) = record(device, &path).expect("record");
        // Stop the writer first, so that the ring fills: the device goes on without waiting.
        writer.stop.store(true, Ordering::Release);
        while !writer.join.as_ref().is_some_and(|j| j.is_finished()) {
            std::thread::sleep(Duration::from_millis(1));
        }
        assert_no_alloc::assert_no_alloc(|| {
            for i in 0..(RING_TICKS as u64 + 100) {
                let _ = device.read_state(i * 1000);
                device.command(ForceTorque::ZERO);
            }
        });
        let stats = writer.finish().expect("finish");
        assert_eq!(stats.dropped, 100);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn a_path_that_cannot_be_created_fails_at_once_and_says_which() {
        let device = SimDevice::new(SimConfig::new(presets::touch()), TargetPath::Hold(haptic_common::Pose::IDENTITY));
        let path = Path::new("/nonexistent-dir/x.trace");
        let e = record(device, path).map(|_| ()).expect_err("no such directory");
        assert!(e.to_string().contains("/nonexistent-dir/x.trace"), "{e}");
    }
}
