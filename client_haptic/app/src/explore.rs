//! The touch bot: explores the copy on the workbench with the stylus and judges it from what it feels.
//!
//! You need this module for `--bot`. It never reads the copy's mesh or material: it knows only what a
//! player knows — which artifact the copy is (its look), where the bench is, and the briefing — and
//! moves the simulated hand along a path of its own:
//! 1. taps: a ring of radial pokes at the height where the kind's features are (the crown's points,
//!    the amphora's ridges, the idol's notches); where each poke first met the surface (or how deep it
//!    got where it met none) is a circular profile whose high runs are counted;
//!    Each poke that met the surface also rests there: the force over the depth since first touch,
//!    median over the pokes, gives the stiffness;
//! 2. a light press on a plain part and a stroke down and up: the drag against the motion over the
//!    normal force gives the friction.

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
/// Friction above which a copy feels rough (briefed: smooth 0.1, rough 0.6; felt through the packed
/// skin's bumps a little higher).
pub const ROUGH_ABOVE: f32 = 0.45;

/// Resting force over depth² (see [`Findings::pressure_n_per_m2`]) above which a copy of `kind` feels
/// hard, N/m². Learnt per kind, like a player learns how a hard crown feels: the crown's thin points give
/// way more than the solid amphora or idol, and on the crown's points and the idol's narrow body a smooth
/// surface lets the stylus slip aside, so those two have one threshold for smooth and one for rough
/// copies (friction is told apart first). Set from the copies of seeds 3, 5 and 11
/// (docs/phantom-client.md); the tests use other seeds.
pub fn hard_above_n_per_m2(kind: ArtifactKind, rough: bool) -> f32 {
    match (kind, rough) {
        (ArtifactKind::Crown, false) => 30_000.0,
        (ArtifactKind::Crown, true) => 140_000.0,
        (ArtifactKind::Amphora, _) => 550_000.0,
        (ArtifactKind::Idol, false) => 60_000.0,
        (ArtifactKind::Idol, true) => 190_000.0,
    }
}

/// Contact force that counts as touching, N.
const TOUCH_N: f32 = 0.05;
/// How far past the surface the hand reaches when pressing to stroke (lightly: the stylus stays in the
/// skin, where the sphere packing is even), m.
const REACH_M: f32 = 0.003;
/// Length of the strokes down and up, m.
const SLIDE_M: f32 = 0.012;

/// Where a kind's features are, from its public look: (height of the ring of pokes, outer radius, inner
/// radius, height of the plain part for the press), metres in the workbench frame.
fn ring(kind: ArtifactKind) -> (f32, f32, f32, f32) {
    let look = artifact::look(kind);
    let (d, h) = (look.size_m[0], look.size_m[1]);
    match kind {
        // The points stand on the rim: poke halfway up them; press the plain band below.
        // The hand reaches only about 7 mm past the plain surface: it feels a face without breaking
        // through it, and still sinks deep where the features leave a gap.
        ArtifactKind::Crown => (0.3 * h, 0.5 * d + 0.015, 0.5 * d - 0.007, 0.0),
        ArtifactKind::Amphora => (-0.08 * h, 0.5 * d + 0.015, 0.5 * d - 0.018, -0.08 * h),
        ArtifactKind::Idol => (-0.15 * h, 0.5 * d + 0.015, 0.5 * d - 0.013, -0.15 * h),
    }
}

/// What the exploration found.
#[derive(Clone, Debug, PartialEq)]
pub struct Findings {
    /// How far in each poke got (distance from the axis), m.
    pub profile: Vec<f32>,
    /// Features counted.
    pub feature_count: u32,
    /// Resting force over depth since first touch on plain parts (median), N/m.
    pub stiffness_n_per_m: f32,
    /// Resting force over depth² (median): the volumetric model's force grows with the depth squared
    /// on a face, so this separates hard from soft by their stiffness ratio, N/m².
    pub pressure_n_per_m2: f32,
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

    /// The figures, for the log.
    pub fn describe(&self) -> String {
        format!(
            "{} features, stiffness {:.0} N/m ({:.0} kN/m²), friction {:.2}: {}",
            self.feature_count,
            self.stiffness_n_per_m,
            self.pressure_n_per_m2 / 1000.0,
            self.friction,
            self.material.adjective()
        )
    }

    /// What the bot says it felt, e.g. "seven points, hard and smooth".
    pub fn spoken(&self, kind: ArtifactKind) -> String {
        let (one, many) = kind.feature_noun();
        let noun = if self.feature_count == 1 { one } else { many };
        format!("{} {noun}, {}", artifact::number_in_words(self.feature_count), self.material.adjective())
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

/// Mean radius and mean inward contact force over the rest at the bottom of a poke.
#[derive(Clone, Copy, Debug, Default)]
struct Hold {
    along: f32,
    force: f32,
    n: u32,
}

impl Hold {
    fn mean(&self) -> Option<(f32, f32)> {
        (self.n > 0).then(|| (self.along / self.n as f32, self.force / self.n as f32))
    }
}

/// One exploration of one copy, stepped by the game thread; the hand moves on the haptic clock.
#[derive(Debug)]
pub struct Exploration {
    kind: ArtifactKind,
    stage: Stage,
    goal: HandGoal,
    stage_start_us: u64,
    stage_end_us: u64,
    taps_start_us: u64,
    tap_touch: Vec<Option<f32>>,
    tap_min: Vec<f32>,
    tap_hold: Vec<Hold>,
    press_angle: f32,
    press_normal: Vec3,
    surface: f32,
    slide: (f32, f32),
    last: Option<(u64, Vec3)>,
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
            stage_end_us: now_us + 1_000_000,
            taps_start_us: 0,
            tap_touch: vec![None; TAPS],
            tap_min: vec![f32::INFINITY; TAPS],
            tap_hold: vec![Hold::default(); TAPS],
            press_angle: 0.0,
            press_normal: Vec3::X,
            surface: 0.0,
            slide: (0.0, 0.0),
            last: None,
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

    /// Whether the exploration is over.
    pub fn done(&self) -> bool {
        self.stage == Stage::Done
    }

    /// Takes this frame's force samples and moves on when a stage ends; returns true when the goal changed.
    pub fn step(&mut self, now_us: u64, samples: &[ForceSample]) -> bool {
        for s in samples {
            self.take(s);
        }
        if now_us < self.stage_end_us || self.stage == Stage::Done {
            return false;
        }
        let (y, r_out, r_in, y_press) = ring(self.kind);
        let start = now_us + 10_000;
        let at = self.goal.sample(now_us).translation;
        let line = |from: Vec3, to: Vec3, duration_s: f32| HandGoal::Line { from, to, duration_s, start_us: start };
        let axis = Vec3::new(0.0, y_press, 0.0);
        let (next, goal, seconds) = match self.stage {
            Stage::Settle => {
                self.taps_start_us = start;
                let taps = HandGoal::Taps {
                    centre: Vec3::new(0.0, y, 0.0),
                    r_out,
                    r_in,
                    n: TAPS as u32,
                    tap_s: TAP_S,
                    start_us: start,
                };
                (Stage::Taps, taps, TAPS as f32 * TAP_S + 0.05)
            }
            Stage::Taps => {
                self.press_angle = self.plain_angle();
                self.press_normal = Vec3::new(self.press_angle.cos(), 0.0, -self.press_angle.sin());
                let k = ((self.press_angle / TAU * TAPS as f32).round() as usize) % TAPS;
                self.surface = self.tap_touch[k].unwrap_or(r_in + 0.007);
                (Stage::Approach, line(at, axis + self.press_normal * r_out, 0.4), 0.5)
            }
            Stage::Approach => (Stage::Press, line(at, axis + self.press_normal * (self.surface - REACH_M), 0.5), 0.8),
            Stage::Press => (Stage::SlideDown, line(at, at - Vec3::Y * SLIDE_M, 0.5), 0.55),
            Stage::SlideDown => (Stage::SlideUp, line(at, at + Vec3::Y * SLIDE_M, 0.5), 0.55),
            Stage::SlideUp => {
                self.findings = Some(self.conclude());
                (Stage::Done, line(at, axis + self.press_normal * (r_out + 0.02), 0.4), 0.4)
            }
            Stage::Done => return false,
        };
        self.stage = next;
        self.stage_start_us = start;
        self.stage_end_us = start + (seconds * 1e6) as u64;
        self.goal = goal;
        true
    }

    fn take(&mut self, s: &ForceSample) {
        let p = s.tool_position;
        let radial = Vec3::new(p.x, 0.0, p.z).length();
        let velocity = match self.last {
            Some((t, q)) if s.t_us > t => (p - q) / ((s.t_us - t) as f32 * 1e-6),
            _ => Vec3::ZERO,
        };
        self.last = Some((s.t_us, p));
        let touching = s.contact_force.length() > TOUCH_N;
        match self.stage {
            Stage::Taps => {
                let since = s.t_us.saturating_sub(self.taps_start_us) as f32 * 1e-6 / TAP_S;
                let (k, u) = (since.floor() as usize, since.fract());
                if k >= TAPS || s.t_us < self.taps_start_us {
                    return;
                }
                // Where the stylus first met the surface on the way in; how deep it got where it met none.
                if u < 0.6 && touching && self.tap_touch[k].is_none() {
                    self.tap_touch[k] = Some(radial);
                }
                if (0.3..0.75).contains(&u) {
                    self.tap_min[k] = self.tap_min[k].min(radial);
                }
                // Resting at the bottom of the poke: how deep, how hard.
                if (0.45..0.6).contains(&u) {
                    let inward = -Vec3::new(p.x, 0.0, p.z).normalize_or_zero();
                    let hold = &mut self.tap_hold[k];
                    hold.along += radial;
                    hold.force += -s.contact_force.dot(inward);
                    hold.n += 1;
                }
            }
            Stage::SlideDown | Stage::SlideUp => {
                let normal = s.contact_force.dot(self.press_normal);
                // Only while really sliding: friction opposes the vertical motion. Summed over both strokes,
                // the packing's bumps push as much with the motion as against it and cancel.
                if normal > TOUCH_N && velocity.y.abs() > 0.005 {
                    self.slide.0 += -s.contact_force.y * velocity.y.signum();
                    self.slide.1 += normal;
                }
            }
            _ => {}
        }
    }

    /// The profile of the taps: where each first touched, or how deep it got.
    fn profile(&self) -> Vec<f32> {
        self.tap_touch
            .iter()
            .zip(&self.tap_min)
            .map(|(touch, min)| touch.unwrap_or(if min.is_finite() { *min } else { 0.0 }))
            .collect()
    }

    /// The angle of a plain part: the crown's band below its points (any angle), the amphora's belly
    /// between ridges, the idol's body between notches.
    fn plain_angle(&self) -> f32 {
        let profile = self.profile();
        let pick = match self.kind {
            ArtifactKind::Crown => return 0.0,
            ArtifactKind::Amphora => lowest_run_middle(&profile),
            ArtifactKind::Idol => lowest_run_middle(&profile.iter().map(|r| -r).collect::<Vec<_>>()),
        };
        TAU * pick as f32 / TAPS as f32
    }

    fn conclude(&self) -> Findings {
        let profile = self.profile();
        let feature_count = match self.kind {
            ArtifactKind::Crown | ArtifactKind::Amphora => artifact::count_high_runs(&profile),
            ArtifactKind::Idol => artifact::count_high_runs(&profile.iter().map(|r| -r).collect::<Vec<_>>()),
        };
        // Stiffness: the median, over the pokes that met a plain part, of the force at rest over the depth
        // since first touch. Plain parts: the amphora's belly (the lower touches; its ridges are narrow
        // and give way), the idol's body and the crown's points (the higher touches).
        let touched: Vec<f32> = self.tap_touch.iter().flatten().copied().collect();
        let (lo, hi) = touched.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &r| (a.min(r), b.max(r)));
        let mid = 0.5 * (lo + hi);
        let plain = |r: f32| if self.kind == ArtifactKind::Amphora { r <= mid } else { r >= mid };
        let rests: Vec<(f32, f32)> = self
            .tap_touch
            .iter()
            .zip(&self.tap_hold)
            .filter_map(|(touch, hold)| {
                let (touch, (at, force)) = ((*touch)?, hold.mean()?);
                (plain(touch) && touch - at > 2e-4 && force > TOUCH_N).then_some((touch - at, force))
            })
            .collect();
        let median = |mut v: Vec<f32>| {
            v.sort_by(f32::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.0)
        };
        let stiffness_n_per_m = median(rests.iter().map(|(d, f)| f / d).collect());
        let pressure_n_per_m2 = median(rests.iter().map(|(d, f)| f / (d * d)).collect());
        let friction = if self.slide.1 > 0.0 { self.slide.0 / self.slide.1 } else { 0.0 };
        let rough = friction > ROUGH_ABOVE;
        let material = match (pressure_n_per_m2 > hard_above_n_per_m2(self.kind, rough), rough) {
            (true, false) => MaterialClass::HardSmooth,
            (true, true) => MaterialClass::HardRough,
            (false, false) => MaterialClass::SoftSmooth,
            (false, true) => MaterialClass::SoftRough,
        };
        Findings { profile, feature_count, stiffness_n_per_m, pressure_n_per_m2, friction, material }
    }
}

/// Places `copy` on the bench of a running [`crate::haptics::Haptics`] (sim device) and explores it;
/// gives up after a minute for the build and a minute for the exploration. Used by the tests and the
/// `feel_copies` example; the client runs the same steps from its systems.
pub fn feel(
    h: &mut crate::haptics::Haptics,
    copy: &heist_shared::protocol::WorkbenchCopy,
    kind: ArtifactKind,
) -> Result<Findings, String> {
    use std::time::{Duration, Instant};
    h.place(copy);
    let deadline = Instant::now() + Duration::from_secs(60);
    while h.on_bench.is_none() {
        if Instant::now() > deadline {
            return Err("the tree was not built within a minute".into());
        }
        if let Some(Err(e)) = h.poll() {
            return Err(e.to_string());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut ex = Exploration::new(kind, h.now_us());
    let map = h.map;
    let hand = |h: &mut crate::haptics::Haptics, goal| {
        h.hand.as_mut().map(|c| c.set(to_device(&map, goal))).ok_or("the device has no steerable hand")
    };
    hand(h, ex.goal())?;
    let deadline = Instant::now() + Duration::from_secs(60);
    while !ex.done() {
        if Instant::now() > deadline {
            return Err("the exploration did not end within a minute".into());
        }
        std::thread::sleep(Duration::from_millis(8));
        h.poll();
        let now = h.now_us();
        if ex.step(now, &h.samples) {
            hand(h, ex.goal())?;
        }
    }
    ex.findings().cloned().ok_or_else(|| "no findings".into())
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
        HandGoal::Line { from, to, duration_s, start_us } => {
            HandGoal::Line { from: d(from), to: d(to), duration_s, start_us }
        }
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
