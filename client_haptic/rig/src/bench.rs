//! The pieces of `haptic-bench`: per-window rates and force magnitudes, the CSV file, the summary and
//! the plot in the style of the paper's Fig. 9.
//!
//! You need this module to analyse timings recorded by a [`HapticRig`](crate::HapticRig) yourself.
//! A window's rate is the number of ticks (or collision steps) that *started* in it divided by its
//! length; windows are aligned half a period before the first tick, so a loop on schedule puts
//! exactly `rate × window` starts in each.

use std::io::Write;

use haptico::TickTiming;
use haptico::timing::{TimingSummary, summarize};

use crate::{ForceSample, StepTiming};

/// One window of the benchmark.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Window {
    /// Start of the window since the first tick, s.
    pub t_s: f64,
    /// Haptic ticks started in the window per second, Hz.
    pub haptic_hz: f64,
    /// Collision steps started in the window per second, Hz.
    pub collision_hz: f64,
    /// Mean force magnitude sent to the device, N.
    pub force_mean_n: f32,
    /// Largest force magnitude, N.
    pub force_max_n: f32,
    /// Mean torque magnitude, N·m.
    pub torque_mean_nm: f32,
    /// Largest torque magnitude, N·m.
    pub torque_max_nm: f32,
    /// Mean contact count per collision step.
    pub contacts_mean: f32,
    /// Collision steps cut short by the time budget.
    pub budget_hits: u32,
    /// Longest collision step, µs.
    pub collision_work_max_us: u32,
    /// CPU time the hypervisor stole around this window (all CPUs, ±one sampling interval), ms.
    pub steal_ms: u64,
}

/// Counts, per window of `window_us`, the starts in `starts_us` (sorted), from `origin_us` on.
pub fn count_per_window(
    starts_us: impl Iterator<Item = u64>,
    origin_us: u64,
    window_us: u64,
    windows: usize,
) -> Vec<u32> {
    let mut counts = vec![0u32; windows];
    for s in starts_us {
        if s < origin_us {
            continue;
        }
        let i = ((s - origin_us) / window_us) as usize;
        if i < windows {
            counts[i] += 1;
        }
    }
    counts
}

/// Builds the windows of a run: `nominal_period_us` aligns them, only complete windows are kept.
pub fn windows(
    haptic: &[TickTiming],
    collision: &[StepTiming],
    forces: &[ForceSample],
    window_us: u64,
    nominal_period_us: u64,
) -> Vec<Window> {
    let (Some(first), Some(last)) = (haptic.first(), haptic.last()) else { return Vec::new() };
    let origin = first.start_us.saturating_sub(nominal_period_us / 2);
    let n = ((last.start_us - origin) / window_us) as usize;
    let per_s = 1e6 / window_us as f64;
    let h = count_per_window(haptic.iter().map(|t| t.start_us), origin, window_us, n);
    let c = count_per_window(collision.iter().map(|t| t.start_us), origin, window_us, n);
    let mut out: Vec<Window> = (0..n)
        .map(|i| Window {
            t_s: (i as u64 * window_us) as f64 * 1e-6,
            haptic_hz: h[i] as f64 * per_s,
            collision_hz: c[i] as f64 * per_s,
            ..Default::default()
        })
        .collect();
    let mut force_n = vec![0u32; n];
    for s in forces {
        if s.t_us < origin {
            continue;
        }
        let i = ((s.t_us - origin) / window_us) as usize;
        if i >= n {
            continue;
        }
        let (f, t) = (s.force.length(), s.torque.length());
        let w = &mut out[i];
        w.force_mean_n += f;
        w.torque_mean_nm += t;
        w.force_max_n = w.force_max_n.max(f);
        w.torque_max_nm = w.torque_max_nm.max(t);
        force_n[i] += 1;
    }
    let mut steps = vec![0u32; n];
    for s in collision {
        if s.start_us < origin {
            continue;
        }
        let i = ((s.start_us - origin) / window_us) as usize;
        if i >= n {
            continue;
        }
        let w = &mut out[i];
        w.contacts_mean += s.contacts as f32;
        w.budget_hits += s.budget_hit as u32;
        w.collision_work_max_us = w.collision_work_max_us.max(s.work_us);
        steps[i] += 1;
    }
    for (i, w) in out.iter_mut().enumerate() {
        if force_n[i] > 0 {
            w.force_mean_n /= force_n[i] as f32;
            w.torque_mean_nm /= force_n[i] as f32;
        }
        if steps[i] > 0 {
            w.contacts_mean /= steps[i] as f32;
        }
    }
    out
}

/// Attributes hypervisor steal to windows: `samples` are (haptic-clock µs, cumulative steal ms) taken
/// every few tens of ms; a window gets the steal between the last sample before it and the first after it.
pub fn add_steal(
    windows: &mut [Window],
    haptic: &[TickTiming],
    samples: &[(u64, u64)],
    window_us: u64,
    nominal_period_us: u64,
) {
    let Some(first) = haptic.first() else { return };
    let origin = first.start_us.saturating_sub(nominal_period_us / 2);
    for (i, w) in windows.iter_mut().enumerate() {
        let (t0, t1) = (origin + i as u64 * window_us, origin + (i as u64 + 1) * window_us);
        let before = samples.iter().rev().find(|s| s.0 <= t0).or(samples.first());
        let after = samples.iter().find(|s| s.0 >= t1).or(samples.last());
        if let (Some(b), Some(a)) = (before, after) {
            w.steal_ms = a.1.saturating_sub(b.1);
        }
    }
}

/// The figures the benchmark reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// Lowest haptic window rate, Hz.
    pub min_haptic_hz: f64,
    /// Lowest collision window rate, Hz.
    pub min_collision_hz: f64,
    /// Haptic period timing.
    pub haptic: TimingSummary,
    /// Collision period timing.
    pub collision: TimingSummary,
    /// Largest force sent, N.
    pub max_force_n: f32,
    /// Largest torque sent, N·m.
    pub max_torque_nm: f32,
    /// Largest force change between ticks, N.
    pub max_force_step_n: f32,
    /// Collision steps cut short by the budget.
    pub budget_hits: u64,
    /// Windows measured.
    pub windows: usize,
}

/// Summarizes a run.
pub fn summary(
    windows: &[Window],
    haptic: &[TickTiming],
    collision: &[StepTiming],
    forces: &[ForceSample],
    nominal_period_us: u32,
) -> Summary {
    let as_ticks: Vec<TickTiming> = collision
        .iter()
        .map(|s| TickTiming { tick: s.sequence, start_us: s.start_us, period_us: s.period_us, work_us: s.work_us })
        .collect();
    let max_force_step_n = forces.windows(2).map(|w| (w[1].force - w[0].force).length()).fold(0.0, f32::max);
    Summary {
        min_haptic_hz: windows.iter().map(|w| w.haptic_hz).fold(f64::INFINITY, f64::min),
        min_collision_hz: windows.iter().map(|w| w.collision_hz).fold(f64::INFINITY, f64::min),
        haptic: summarize(haptic, nominal_period_us),
        collision: summarize(&as_ticks, nominal_period_us),
        max_force_n: forces.iter().map(|s| s.force.length()).fold(0.0, f32::max),
        max_torque_nm: forces.iter().map(|s| s.torque.length()).fold(0.0, f32::max),
        max_force_step_n,
        budget_hits: collision.iter().filter(|s| s.budget_hit).count() as u64,
        windows: windows.len(),
    }
}

/// What the collision steps cost: their work time's median and 99th percentile, the broad phase's part
/// of it, and how many pairs a step queried and skipped.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepCosts {
    /// Median work time of a step, µs.
    pub work_p50_us: u32,
    /// 99th percentile of a step's work time, µs.
    pub work_p99_us: u32,
    /// 99th percentile of the time spent reading poses and in the broad phase, µs.
    pub broad_p99_us: f32,
    /// The broad phase's share of all the steps' work (0–1).
    pub broad_share: f32,
    /// Pairs queried per step, on average.
    pub queried_mean: f32,
    /// Pairs the broad phase skipped per step, on average.
    pub culled_mean: f32,
}

/// The costs of the recorded collision steps.
pub fn step_costs(collision: &[StepTiming]) -> StepCosts {
    if collision.is_empty() {
        return StepCosts::default();
    }
    let percentile = |mut values: Vec<u32>, q: f64| {
        values.sort_unstable();
        values[((values.len() - 1) as f64 * q).round() as usize]
    };
    let work: Vec<u32> = collision.iter().map(|s| s.work_us).collect();
    let broad: Vec<u32> = collision.iter().map(|s| s.broad_ns).collect();
    let n = collision.len() as f32;
    let work_ns: f64 = collision.iter().map(|s| s.work_us as f64 * 1000.0).sum();
    let broad_ns: f64 = collision.iter().map(|s| s.broad_ns as f64).sum();
    StepCosts {
        work_p50_us: percentile(work.clone(), 0.5),
        work_p99_us: percentile(work, 0.99),
        broad_p99_us: percentile(broad, 0.99) as f32 / 1000.0,
        broad_share: if work_ns > 0.0 { (broad_ns / work_ns) as f32 } else { 0.0 },
        queried_mean: collision.iter().map(|s| s.queried as f32).sum::<f32>() / n,
        culled_mean: collision.iter().map(|s| s.culled as f32).sum::<f32>() / n,
    }
}

/// Writes the windows as CSV (header + one line per window).
pub fn write_csv(out: &mut impl Write, windows: &[Window]) -> std::io::Result<()> {
    writeln!(
        out,
        "t_s,haptic_hz,collision_hz,force_mean_n,force_max_n,torque_mean_nm,torque_max_nm,contacts_mean,budget_hits,collision_work_max_us,steal_ms"
    )?;
    for w in windows {
        writeln!(
            out,
            "{:.1},{:.0},{:.0},{:.4},{:.4},{:.5},{:.5},{:.1},{},{},{}",
            w.t_s,
            w.haptic_hz,
            w.collision_hz,
            w.force_mean_n,
            w.force_max_n,
            w.torque_mean_nm,
            w.torque_max_nm,
            w.contacts_mean,
            w.budget_hits,
            w.collision_work_max_us,
            w.steal_ms
        )?;
    }
    Ok(())
}

/// Draws the Fig. 9-style plot: window rates on top, force and torque magnitudes below.
#[cfg(feature = "bench")]
pub fn plot(path: &std::path::Path, windows: &[Window], title: &str) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let root = BitMapBackend::new(path, (1000, 620)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(330);
    let t_max = windows.last().map_or(1.0, |w| w.t_s + 0.1);
    let hz_max = windows.iter().map(|w| w.haptic_hz.max(w.collision_hz)).fold(1200.0, f64::max) * 1.05;

    let mut chart = ChartBuilder::on(&top)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t_max, 0.0..hz_max)?;
    chart.configure_mesh().x_desc("time (s)").y_desc("rate per 100 ms window (Hz)").draw()?;
    chart
        .draw_series(LineSeries::new(windows.iter().map(|w| (w.t_s, w.haptic_hz)), BLUE.stroke_width(2)))?
        .label("haptic loop")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(windows.iter().map(|w| (w.t_s, w.collision_hz)), RED.stroke_width(2)))?
        .label("collision detection")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    chart.draw_series(LineSeries::new([(0.0, 1000.0), (t_max, 1000.0)], BLACK.mix(0.3)))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;

    let f_max = windows.iter().map(|w| w.force_max_n).fold(0.1, f32::max) as f64 * 1.1;
    let tau_max = windows.iter().map(|w| w.torque_max_nm).fold(0.001, f32::max) as f64 * 1.1;
    let mut chart = ChartBuilder::on(&bottom)
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .right_y_label_area_size(60)
        .build_cartesian_2d(0.0..t_max, 0.0..f_max)?
        .set_secondary_coord(0.0..t_max, 0.0..tau_max);
    chart.configure_mesh().x_desc("time (s)").y_desc("|force| (N)").draw()?;
    chart.configure_secondary_axes().y_desc("|torque| (N·m)").draw()?;
    chart
        .draw_series(LineSeries::new(windows.iter().map(|w| (w.t_s, w.force_mean_n as f64)), GREEN.stroke_width(2)))?
        .label("|force| (window mean)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], GREEN.stroke_width(2)));
    chart
        .draw_secondary_series(LineSeries::new(
            windows.iter().map(|w| (w.t_s, w.torque_mean_nm as f64)),
            MAGENTA.stroke_width(2),
        ))?
        .label("|torque| (window mean)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], MAGENTA.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn ticks(period_us: u64, n: u64, start: u64) -> Vec<TickTiming> {
        (0..n)
            .map(|i| TickTiming {
                tick: i,
                start_us: start + i * period_us,
                period_us: if i == 0 { 0 } else { period_us as u32 },
                work_us: 10,
            })
            .collect()
    }

    #[test]
    fn step_costs_are_percentiles_of_the_work_and_the_broad_phase_share() {
        // 100 steps of 10..=109 µs, each with 1 µs of broad phase, 3 pairs queried and 250 skipped.
        let steps: Vec<StepTiming> = (0..100u32)
            .map(|i| StepTiming { work_us: 10 + i, broad_ns: 1000, queried: 3, culled: 250, ..Default::default() })
            .collect();
        let c = step_costs(&steps);
        assert_eq!((c.work_p50_us, c.work_p99_us, c.broad_p99_us), (60, 108, 1.0));
        assert!((c.broad_share - 100_000.0 / 5_950_000.0).abs() < 1e-6, "{c:?}");
        assert_eq!((c.queried_mean, c.culled_mean), (3.0, 250.0));
        assert_eq!(step_costs(&[]), StepCosts::default());
    }

    #[test]
    fn a_loop_on_schedule_puts_exactly_its_rate_in_every_window() {
        let h = ticks(1000, 1000, 12_345);
        let w = windows(&h, &[], &[], 100_000, 1000);
        assert_eq!(w.len(), 9);
        assert!(w.iter().all(|w| w.haptic_hz == 1000.0), "{w:?}");
    }

    #[test]
    fn a_stall_shows_up_as_a_low_window() {
        let mut h = ticks(1000, 1000, 0);
        h.retain(|t| !(250_000..260_000).contains(&t.start_us));
        let w = windows(&h, &[], &[], 100_000, 1000);
        assert_eq!(w[2].haptic_hz, 900.0);
        let s = summary(&w, &h, &[], &[], 1000);
        assert_eq!(s.min_haptic_hz, 900.0);
    }

    #[test]
    fn forces_are_averaged_per_window_and_the_largest_step_is_found() {
        let h = ticks(1000, 300, 0);
        let f: Vec<ForceSample> = (0..300u64)
            .map(|i| ForceSample {
                t_us: i * 1000,
                force: Vec3::X * if i < 150 { 1.0 } else { 2.0 },
                ..Default::default()
            })
            .collect();
        let w = windows(&h, &[], &f, 100_000, 1000);
        assert!((w[0].force_mean_n - 1.0).abs() < 1e-6 && w[1].force_max_n == 2.0);
        let s = summary(&w, &h, &[], &f, 1000);
        assert_eq!(s.max_force_step_n, 1.0);
    }

    #[test]
    fn csv_has_a_header_and_one_line_per_window() {
        let w = windows(&ticks(1000, 500, 0), &[], &[], 100_000, 1000);
        let mut out = Vec::new();
        write_csv(&mut out, &w).expect("write");
        let text = String::from_utf8(out).expect("utf8");
        assert_eq!(text.lines().count(), w.len() + 1);
        assert!(text.starts_with("t_s,haptic_hz,collision_hz"));
    }
}
