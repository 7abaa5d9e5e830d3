//! The touch bot: explores the copy on the workbench with the stylus and judges it from what it feels.
//!
//! You need this module for `--bot`. It never reads the copy's mesh or material: it knows only what a
//! player knows — which artifact the copy is (its look), where the bench is, and the briefing — and
//! moves the simulated hand along a path of its own:
//! 1. taps: a ring of radial pokes at the height where the kind's features are (the crown's points,
//!    the amphora's ridges, the idol's notches); how far in each poke got is a circular profile whose
//!    high runs are counted;
//! 2. a press on a plain part: the contact force over the depth since first touch gives the stiffness;
//! 3. a stroke down and up while pressing: the vertical drag over the normal force gives the friction.

use std::f32::consts::TAU;

use glam::Vec3;
use haptic_common::Pose;
use haptic_rig::ForceSample;
use heist_shared::artifact::{self, ArtifactKind, Briefing, MaterialClass};

use crate::device::HandGoal;

/// Pokes around the copy.
pub const TAPS: usize = 48;
/// Seconds per poke.
pub const TAP_S: f32 = 0.4;
/// Secant stiffness above which a copy feels hard, N/m (hard copies read ≈ 800, soft ≈ 450 on flat faces).
pub const HARD_ABOVE_N_PER_M: f32 = 600.0;
/// Friction above which a copy feels rough (smooth 0.1, rough 0.6).
pub const ROUGH_ABOVE: f32 = 0.3;
/// Contact force that counts as touching, N.
const TOUCH_N: f32 = 0.05;
/// How far past the expected surface the hand reaches, m.
const REACH_M: f32 = 0.012;

/// Where a kind's features are, from its public look: (height of the ring of pokes, outer radius, inner
/// radius, height of the plain part for the press), metres in the workbench frame.
fn ring(kind: ArtifactKind) -> (f32, f32, f32, f32) {
    let look = artifact::look(kind);
    let (d, h) = (look.size_m[0], look.size_m[1]);
    match kind {
        // The points stand on the rim: poke halfway up them; press the plain band below.
        ArtifactKind::Crown => (0.3 * h, 0.5 * d + 0.015, 0.5 * d - 0.015, 0.0),
        ArtifactKind::Amphora => (-0.08 * h, 0.5 * d + 0.015, 0.5 * d - 0.025, -0.08 * h),
        ArtifactKind::Idol => (-0.15 * h, 0.5 * d + 0.015, 0.5 * d - 0.02, -0.15 * h),
    }
}

/// What the exploration found.
#[derive(Clone, Debug, PartialEq)]
pub struct Findings {
    /// How far in each poke got (distance from the axis), m.
    pub profile: Vec<f32>,
    /// Features counted.
    pub feature_count: u32,
    /// Secant stiffness at the press, N/m.
    pub stiffness_n_per_m: f32,
    /// Friction coefficient from the stroke.
    pub friction: f32,
    /// The material class these make.
    pub material: MaterialClass,
}

impl Findings {
    /// Whether the copy matches the briefing.
    pub fn matches(&self, briefing: &Briefing) -> bool {
        self.feature_count == briefing.feature_count && self.material == briefing.material
    }

    /// A sentence for the log and for speech.
    pub fn describe(&self) -> String {
        format!(
            "{} features, stiffness {:.0} newtons per metre, friction {:.2}: {}",
            self.feature_count,
            self.stiffness_n_per_m,
            self.friction,
            match self.material {
                MaterialClass::HardSmooth => "hard and smooth",
                MaterialClass::HardRough => "hard and rough",
                MaterialClass::SoftSmooth => "soft and smooth",
                MaterialClass::SoftRough => "soft and rough",
            }
        )
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    Settle,
    Taps,
    Approach,
    Press,
    SlideDown,
    SlideUp,
    Done,
}

/// One exploration of one copy, stepped by the game thread; the hand moves on the haptic clock.
#[derive(Debug)]
pub struct Exploration {
    kind: ArtifactKind,
    stage: Stage,
    goal: HandGoal,
    stage_start_us: u64,
    taps_start_us: u64,
    tap_min: Vec<f32>,
    press_angle: f32,
    press_normal: Vec3,
    first_touch_r: Option<f32>,
    press: Vec<(f32, f32)>,
    slide: [(f32, f32, u32); 2],
    findings: Option<Findings>,
}

impl Exploration {
    /// Starts exploring a copy of `kind` at haptic-clock time `now_us`.
    pub fn new(kind: ArtifactKind, now_us: u64) -> Self {
        let (y, r_out, ..) = ring(kind);
        Self {
            kind,
            stage: Stage::Settle,
            goal: HandGoal::Line {
                from: Vec3::new(r_out, y + 0.05, 0.0),
                to: Vec3::new(r_out, y, 0.0),
                duration_s: 0.6,
                start_us: now_us,
            },
            stage_start_us: now_us,
            taps_start_us: 0,
            tap_min: vec![f32::INFINITY; TAPS],
            press_angle: 0.0,
            press_normal: Vec3::X,
            first_touch_r: None,
            press: Vec::with_capacity(4096),
            slide: [(0.0, 0.0, 0); 2],
            findings: None,
        }
    }

    /// Where the hand should go now (scene frame).
    pub fn goal(&self) -> HandGoal {
        self.goal
    }

    /// The result, once done.
    pub fn findings(&self) -> Option<&Findings> {
        self.findings.as_ref()
    }

    /// Takes this frame's force samples and moves on when a stage ends; returns true when the goal changed.
    pub fn step(&mut self, now_us: u64, samples: &[ForceSample]) -> bool {
        let (y, r_out, r_in, y_press) = ring(self.kind);
        for s in samples {
            self.take(s, y_press);
        }
        let elapsed_s = now_us.saturating_sub(self.stage_start_us) as f32 * 1e-6;
        let start = now_us + 10_000;
        let (next, goal) = match self.stage {
            Stage::Settle if elapsed_s > 1.0 => {
                self.taps_start_us = start;
                (Stage::Taps, HandGoal::Taps { centre: Vec3::new(0.0, y, 0.0), r_out, r_in, n: TAPS as u32, tap_s: TAP_S, start_us: start })
            }
            Stage::Taps if elapsed_s > TAPS as f32 * TAP_S + 0.05 => {
                self.press_angle = self.plain_angle();
                let dir = Vec3::new(self.press_angle.cos(), 0.0, -self.press_angle.sin());
                self.press_normal = dir;
                let from = Vec3::new(0.0, y_press, 0.0) + dir * r_out;
                (Stage::Approach, HandGoal::Line { from: self.goal.sample(now_us).translation, to: from, duration_s: 0.4, start_us: start })
            }
            Stage::Approach if elapsed_s > 0.5 => {
                let from = Vec3::new(0.0, y_press, 0.0) + self.press_normal * r_out;
                let to = Vec3::new(0.0, y_press, 0.0) + self.press_normal * (self.expected_surface(r_in) - REACH_M);
                self.first_touch_r = None;
                (Stage::Press, HandGoal::Line { from, to, duration_s: 0.8, start_us: start })
            }
            Stage::Press if elapsed_s > 1.4 => {
                let at = self.goal.sample(now_us).translation;
                (Stage::SlideDown, HandGoal::Line { from: at, to: at - Vec3::Y * 0.01, duration_s: 0.4, start_us: start })
            }
            Stage::SlideDown if elapsed_s > 0.45 => {
                let at = self.goal.sample(now_us).translation;
                (Stage::SlideUp, HandGoal::Line { from: at, to: at + Vec3::Y * 0.01, duration_s: 0.4, start_us: start })
            }
            Stage::SlideUp if elapsed_s > 0.45 => {
                self.findings = Some(self.conclude());
                let at = self.goal.sample(now_us).translation;
                let away = Vec3::new(0.0, y_press, 0.0) + self.press_normal * (r_out + 0.02);
                (Stage::Done, HandGoal::Line { from: at, to: away, duration_s: 0.4, start_us: start })
            }
            _ => return false,
        };
        self.stage = next;
        self.stage_start_us = now_us;
        self.goal = goal;
        true
    }

    /// Whether the exploration is over.
    pub fn done(&self) -> bool {
        self.stage == Stage::Done
    }

    fn take(&mut self, s: &ForceSample, y_press: f32) {
        let p = s.tool_position;
        let radial = Vec3::new(p.x, 0.0, p.z).length();
        match self.stage {
            Stage::Taps => {
                let since = s.t_us.saturating_sub(self.taps_start_us) as f32 * 1e-6 / TAP_S;
                let (k, u) = (since.floor() as usize, since.fract());
                // The bottom of the poke: where the hand stopped, on the surface or deep in a gap.
                if k < TAPS && (0.3..0.75).contains(&u) {
                    self.tap_min[k] = self.tap_min[k].min(radial);
                }
            }
            Stage::Press => {
                let along = p.dot(self.press_normal);
                let f = s.contact_force.dot(self.press_normal);
                if self.first_touch_r.is_none() && f > TOUCH_N {
                    self.first_touch_r = Some(along);
                }
                if self.press.len() < self.press.capacity() {
                    self.press.push((along, f));
                }
            }
            Stage::SlideDown | Stage::SlideUp => {
                let i = usize::from(self.stage == Stage::SlideUp);
                let normal = s.contact_force.dot(self.press_normal);
                if normal > TOUCH_N && (p.y - y_press).abs() < 0.02 {
                    self.slide[i].0 += s.contact_force.y;
                    self.slide[i].1 += normal;
                    self.slide[i].2 += 1;
                }
            }
            _ => {}
        }
    }

    /// Where the surface was expected at the press angle: the poke there, or the outer radius.
    fn expected_surface(&self, r_in: f32) -> f32 {
        let k = ((self.press_angle / TAU * TAPS as f32).round() as usize) % TAPS;
        let r = self.tap_min[k];
        if r.is_finite() && r > r_in + 0.003 { r } else { ring(self.kind).1 - 0.015 }
    }

    /// The angle of a plain part: between two points (crown: any, it is pressed below them), on the
    /// amphora's belly between ridges, on the idol's body between notches.
    fn plain_angle(&self) -> f32 {
        let profile: Vec<f32> = self.tap_min.iter().map(|r| if r.is_finite() { *r } else { 0.0 }).collect();
        let pick = match self.kind {
            ArtifactKind::Crown => return 0.0,
            ArtifactKind::Amphora => lowest_run_middle(&profile),
            ArtifactKind::Idol => lowest_run_middle(&profile.iter().map(|r| -r).collect::<Vec<_>>()),
        };
        TAU * pick as f32 / TAPS as f32
    }

    fn conclude(&self) -> Findings {
        let profile: Vec<f32> = self.tap_min.iter().map(|r| if r.is_finite() { *r } else { 0.0 }).collect();
        let feature_count = match self.kind {
            ArtifactKind::Crown | ArtifactKind::Amphora => artifact::count_high_runs(&profile),
            ArtifactKind::Idol => artifact::count_high_runs(&profile.iter().map(|r| -r).collect::<Vec<_>>()),
        };
        // Stiffness: the force of the last third of the press over how deep the tool sank since first touch.
        let tail = &self.press[self.press.len() * 2 / 3..];
        let (depth, force) = match (self.first_touch_r, tail.is_empty()) {
            (Some(touch), false) => {
                let n = tail.len() as f32;
                let along = tail.iter().map(|s| s.0).sum::<f32>() / n;
                let f = tail.iter().map(|s| s.1).sum::<f32>() / n;
                (touch - along, f)
            }
            _ => (0.0, 0.0),
        };
        let stiffness_n_per_m = if depth > 1e-4 { force / depth } else { 0.0 };
        let mean = |(fy, fnormal, n): (f32, f32, u32)| if n > 0 { (fy / n as f32, fnormal / n as f32) } else { (0.0, 0.0) };
        let ((down_fy, down_n), (up_fy, up_n)) = (mean(self.slide[0]), mean(self.slide[1]));
        // Sliding down, friction pushes the tool up; sliding up, down: half the difference is μ·N.
        let normal = 0.5 * (down_n + up_n);
        let friction = if normal > TOUCH_N { (down_fy - up_fy) / (2.0 * normal) } else { 0.0 };
        let material = match (stiffness_n_per_m > HARD_ABOVE_N_PER_M, friction > ROUGH_ABOVE) {
            (true, false) => MaterialClass::HardSmooth,
            (true, true) => MaterialClass::HardRough,
            (false, false) => MaterialClass::SoftSmooth,
            (false, true) => MaterialClass::SoftRough,
        };
        Findings { profile, feature_count, stiffness_n_per_m, friction, material }
    }
}

/// Index at the middle of the longest stretch within 25 % of the profile's minimum.
fn lowest_run_middle(profile: &[f32]) -> usize {
    let n = profile.len();
    let (min, max) = profile.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let low = |i: usize| profile[i % n] <= min + 0.25 * (max - min);
    let mut best = (0, 0);
    for start in 0..n {
        if low(start) && !low(start + n - 1) {
            let len = (0..n).take_while(|&j| low(start + j)).count();
            if len > best.1 {
                best = (start, len);
            }
        }
    }
    if best.1 == 0 { 0 } else { (best.0 + best.1 / 2) % n }
}

/// The pose a goal asks for, in the device frame of `map`.
pub fn to_device(map: &haptic_rig::WorkspaceMap, goal: HandGoal) -> HandGoal {
    let d = |p: Vec3| map.to_device(&Pose::from_translation(p)).translation;
    match goal {
        HandGoal::Hold(p) => HandGoal::Hold(map.to_device(&p)),
        HandGoal::Line { from, to, duration_s, start_us } => HandGoal::Line { from: d(from), to: d(to), duration_s, start_us },
        HandGoal::Orbit { centre, radius, start_rad, period_s, turns, start_us } => {
            HandGoal::Orbit { centre: d(centre), radius: radius / map.scale, start_rad, period_s, turns, start_us }
        }
        HandGoal::Taps { centre, r_out, r_in, n, tap_s, start_us } => {
            HandGoal::Taps { centre: d(centre), r_out: r_out / map.scale, r_in: r_in / map.scale, n, tap_s, start_us }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plain_part_is_the_middle_of_the_longest_low_stretch() {
        let mut p = vec![1.0; 12];
        p[3] = 0.0;
        p[7] = 0.0;
        p[8] = 0.0;
        p[9] = 0.0;
        assert_eq!(lowest_run_middle(&p), 8);
        let mut wrap = vec![1.0; 12];
        wrap[11] = 0.0;
        wrap[0] = 0.0;
        wrap[1] = 0.0;
        assert_eq!(lowest_run_middle(&wrap), 0);
    }
}
