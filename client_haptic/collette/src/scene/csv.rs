//! Trajectory files: CSV so any tool (and any other benchmark) can replay the same path.
//!
//! Format: lines starting with `#` are comments; one header line
//! `t_s,phase,x_m,y_m,z_m,qx,qy,qz,qw`; then one line per sample: time in seconds, phase (`free`,
//! `grazing`, `deep`), the tool's world translation in metres and its rotation quaternion. Numbers are
//! written in Rust's shortest round-trip form, so reading gives back exactly the samples written.

use super::{Phase, TrajectorySample};
use crate::error::TrajectoryError;
use glam::{Quat, Vec3};
use haptic_common::Pose;
use std::io::{BufRead, BufWriter, Write};
use std::path::Path;

const HEADER: &str = "t_s,phase,x_m,y_m,z_m,qx,qy,qz,qw";

/// Writes `samples` to `path` (created or truncated).
///
/// Format: lines starting with `#` are comments; one header line `t_s,phase,x_m,y_m,z_m,qx,qy,qz,qw`;
/// then one line per sample: time in seconds, phase (`free`, `grazing`, `deep`), the tool's world
/// translation in metres and its rotation quaternion, in Rust's shortest round-trip number form.
pub fn write_trajectory_csv(path: impl AsRef<Path>, samples: &[TrajectorySample]) -> Result<(), TrajectoryError> {
    let path = path.as_ref();
    let io = |source| TrajectoryError::Io { path: path.to_owned(), source };
    let mut w = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    let mut write = || -> std::io::Result<()> {
        writeln!(w, "# collette bunny-scene trajectory v1: tool pose per sample, bunny at the identity pose")?;
        writeln!(w, "{HEADER}")?;
        for s in samples {
            let (p, q) = (s.tool.translation, s.tool.rotation);
            writeln!(w, "{},{},{},{},{},{},{},{},{}", s.time_s, s.phase.as_str(), p.x, p.y, p.z, q.x, q.y, q.z, q.w)?;
        }
        w.flush()
    };
    write().map_err(io)
}

/// Reads a file written by [`write_trajectory_csv`].
pub fn read_trajectory_csv(path: impl AsRef<Path>) -> Result<Vec<TrajectorySample>, TrajectoryError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| TrajectoryError::Io { path: path.to_owned(), source })?;
    let mut out = Vec::new();
    for (i, line) in std::io::BufReader::new(file).lines().enumerate() {
        let line = line.map_err(|source| TrajectoryError::Io { path: path.to_owned(), source })?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line == HEADER {
            continue;
        }
        let err = |message: String| TrajectoryError::Parse { path: path.to_owned(), line: i + 1, message };
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != 9 {
            return Err(err(format!("expected 9 fields, found {}", fields.len())));
        }
        let phase = Phase::parse(fields[1]).ok_or_else(|| err(format!("unknown phase {:?}", fields[1])))?;
        let time_s: f64 = fields[0].parse().map_err(|_| err(format!("bad time {:?}", fields[0])))?;
        let mut n = [0f32; 7];
        for (k, f) in fields[2..].iter().enumerate() {
            n[k] = f.parse().map_err(|_| err(format!("bad number {f:?}")))?;
        }
        let tool = Pose::new(Vec3::new(n[0], n[1], n[2]), Quat::from_xyzw(n[3], n[4], n[5], n[6]));
        if !tool.is_finite() {
            return Err(err("non-finite pose".into()));
        }
        out.push(TrajectorySample { time_s, tool, phase });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_trajectory_reads_back_identically_and_garbage_is_an_error() {
        let dir = std::env::temp_dir().join(format!("collette-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let samples: Vec<_> = (0..10)
            .map(|i| TrajectorySample {
                time_s: i as f64 * 0.001,
                tool: Pose::new(Vec3::new(0.1 * i as f32, -0.3, 1e-7), Quat::from_rotation_y(0.1 * i as f32)),
                phase: [Phase::Free, Phase::Grazing, Phase::Deep][i % 3],
            })
            .collect();
        let path = dir.join("t.csv");
        write_trajectory_csv(&path, &samples).expect("write");
        assert_eq!(read_trajectory_csv(&path).expect("read"), samples);
        std::fs::write(&path, format!("{HEADER}\n0.0,free,1,2\n")).expect("write");
        assert!(matches!(read_trajectory_csv(&path), Err(TrajectoryError::Parse { line: 2, .. })));
        std::fs::remove_dir_all(&dir).ok();
    }
}
