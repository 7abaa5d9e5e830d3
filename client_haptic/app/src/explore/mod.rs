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
//!    normal force gives the friction, and a push along the stroke that repeats with the height gives the
//!    ridges: a copy with ridges ([`RIDGES_ABOVE`]) that grips ([`ROUGH_ABOVE`]) is rough (ribbed).
//!    A stroke that was mostly out of touch (the press met nothing) says nothing, and says the pokes
//!    went wrong where the press went (the surface was not where they found it): the exploration starts
//!    over while another of its [`ATTEMPTS`] is allowed; on the last one the hand backs off and presses
//!    again, a little deeper, up to [`ATTEMPTS`] times.
//!
//! A hand can only judge what it felt at full force: when the haptic loop stalls (the process was not
//! scheduled) or the contact data goes stale, the safety layer fades the forces out and back in over two
//! seconds, the stylus sinks where a wall should have stopped it, and a narrow copy can feel like
//! nothing at all. An exploration that measured during such a spell backs off round the copy, waits
//! until the forces are whole again and starts over, up to [`ATTEMPTS`] times. A single poke can also
//! go wrong with the forces whole: the stylus fails to follow the hand (it met nothing, yet never got
//! in) or first touches where no copy reaches; one such poke would read as a feature (or as the only
//! plain part to rest on), so a missed poke reads as the poke before it and is never rested on.

mod profile;

use std::f32::consts::TAU;

use glam::Vec3;
use haptic_rig::ForceSample;
use heist_shared::artifact::{self, ArtifactKind, Briefing, MaterialClass};

use crate::device::{HandGoal, to_device};
use crate::haptics::TOOL_DIAMETER_M;
use crate::touch_bench::TouchBench;
pub use profile::RIDGES_ABOVE;
use profile::{SLIDE_M, StrokeSample, TOUCH_N, count_notches, lowest_run_middle, median, strongest_repeat};

/// Pokes around an amphora.
pub const TAPS: usize = 48;
/// Pokes around an idol or a crown: an idol's V notches are narrow at the depth the stylus reaches, and
/// with 48 pokes (4.7 mm apart) one whose bottom fell between two pokes read shallow; so did the narrow
/// gaps between a nine-pointed crown's points (45.8 and 46.2 mm where the others read 41.5 and the points
/// 52.5: two pairs of points read as one each, 7 of 9, heist seed 10). 96 pokes take 19 s longer.
pub const IDOL_TAPS: usize = 96;

/// Pokes around a copy of `kind`.
pub fn taps(kind: ArtifactKind) -> usize {
    if kind == ArtifactKind::Amphora { TAPS } else { IDOL_TAPS }
}
/// Seconds per poke.
pub const TAP_S: f32 = 0.4;
/// Friction above which a copy grips like a rough one (briefed: smooth 0.1, rough 0.6; felt through
/// the packed skin's bumps a little higher). A ribbed copy must grip too: on a narrow soft idol the
/// packing's bumps alone repeated as strongly as ridges (0.24, volumetric rendering, seed 24, before the
/// copy had a surface grid; since, smooth copies repeat at most 0.02 through it).
pub const ROUGH_ABOVE: f32 = 0.45;
/// Explorations of one copy at most, when the first ones were disturbed.
pub const ATTEMPTS: u32 = 3;
/// A tick this much later than the one before means the haptic loop stalled, µs.
const STALL_US: u64 = 50_000;
/// Contact data older than this trips the safety layer's watchdog (at its default timeout), µs.
const STALE_US: u32 = (forcecomp::safety::DEFAULT_WATCHDOG_TIMEOUT_S * 1e6) as u32;
/// How long forces are suspect after a stall or stale data: the watchdog's ramp back in (its default)
/// and half a second's margin, µs.
const RECOVER_US: u64 = ((forcecomp::safety::DEFAULT_RAMP_IN_S + 0.5) * 1e6) as u64;

/// Resting force over depth² (see [`Findings::pressure_n_per_m2`]) above which a copy feels hard through
/// the volumetric rendering, N/m², whatever its kind and roughness: the gemstone is measured against the
/// copy's surface grid, so a copy pushes back as its briefing says wherever the stylus rests (felt on the
/// copies of seeds 3, 5 and 11: soft 192–310, hard 646–1,430 kN/m²; docs/phantom-client.md). Until the
/// copy had a surface grid (2026-12-05) it was learnt per kind and roughness, 30–550 kN/m²: the packing's
/// hollows gave way under a smooth crown's points or a narrow idol's body.
pub const HARD_ABOVE_N_PER_M2: f32 = 450_000.0;

/// How far past the surface the hand reaches when pressing to stroke (lightly: the stylus stays in the
/// skin, where the sphere packing is even), m.
const REACH_M: f32 = 0.003;
/// How much deeper each press after one that met nothing reaches, m.
const DEEPER_M: f32 = 0.002;
/// A touch this much farther out than an idol's median touch is not on the idol, m (its body's touches
/// spread by about ±1 mm).
const SPIKE_M: f32 = 0.0025;
/// Pokes either side of the press's angle whose touches give the surface pressed.
const PRESS_SPAN: usize = 2;

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
    /// The strongest repeat felt along the strokes: (spacing, m; its push along the stroke over the
    /// normal force). Ridges when that passes [`RIDGES_ABOVE`]; None when the strokes barely touched.
    pub ridges: Option<(f32, f32)>,
    /// The material class these make (ribbed when ridges were felt).
    pub material: MaterialClass,
    /// Explorations it took (more than one when the haptic loop was disturbed during one, or when the
    /// first stroke of one met nothing).
    pub attempts: u32,
    /// Explorations started over because their first stroke met nothing where their pokes had found
    /// the surface.
    pub unconfirmed: u32,
    /// Presses in the last exploration (more than one when a stroke was mostly out of touch).
    pub presses: u32,
    /// Share of the last stroke's sliding samples that were in touch, 0–1.
    pub stroke_contact: f32,
    /// Whether the last exploration was disturbed too (after [`ATTEMPTS`]): the figures are suspect.
    pub disturbed: bool,
    /// What disturbed the haptic loop during the explorations (the first few spells of each), for the log.
    pub disturbances: Vec<Disturbance>,
}

/// A spell in which the forces were not whole: the haptic loop stalled or the contact data went stale
/// (it spoils the exploration when a stage measured within 2.5 s of it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disturbance {
    /// Which exploration (1-based).
    pub attempt: u32,
    /// Seconds since the exploration of the copy began.
    pub at_s: f32,
    /// The gap between two haptic ticks (a stall) or the contact data's age (stale data), ms.
    pub gap_ms: f32,
    /// True for stale contact data, false for a stall.
    pub stale: bool,
    stage: Stage,
}

/// Spells of disturbance recorded per exploration.
const MAX_DISTURBANCES: usize = 4;

impl Findings {
    /// Whether the copy matches the briefing.
    pub fn matches(&self, briefing: &Briefing) -> bool {
        self.feature_count == briefing.feature_count && self.material == briefing.material
    }

    /// The figures, for the log.
    pub fn describe(&self) -> String {
        let attempts = match (self.attempts, self.disturbed, self.unconfirmed) {
            (_, true, _) => format!(" (disturbed in all {} explorations)", self.attempts),
            (1, false, _) => String::new(),
            (n, false, 0) => format!(" ({n} explorations: the earlier ones were disturbed)"),
            (n, false, u) => format!(" ({n} explorations: {u} with a first stroke that met nothing)"),
        };
        let why: Vec<String> = self
            .disturbances
            .iter()
            .map(|d| {
                let what = if d.stale { "stale contact data" } else { "a stall" };
                let stage = format!("{:?}", d.stage).to_lowercase();
                format!("{what} of {:.0} ms at {:.1} s ({stage}, exploration {})", d.gap_ms, d.at_s, d.attempt)
            })
            .collect();
        let attempts = if why.is_empty() { attempts } else { format!("{attempts} [{}]", why.join("; ")) };
        let presses = match self.presses {
            0 | 1 => String::new(),
            n => format!(" ({n} presses: the earlier strokes met nothing)"),
        };
        let ridges = match self.ridges {
            Some((spacing, strength)) => format!(
                "{} (strongest repeat every {:.1} mm, {strength:.2})",
                if strength > RIDGES_ABOVE { "ridges" } else { "no ridges" },
                spacing * 1000.0
            ),
            None => "no ridges (the strokes barely touched)".to_string(),
        };
        format!(
            "{} features, stiffness {:.0} N/m ({:.0} kN/m²), friction {:.2}, {ridges} ({:.0} % of the stroke in touch): {}{attempts}{presses}",
            self.feature_count,
            self.stiffness_n_per_m,
            self.pressure_n_per_m2 / 1000.0,
            self.friction,
            100.0 * self.stroke_contact,
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
    /// From wherever the hand is, straight out from the copy's axis to the ring of pokes' radius (or
    /// stays out where it is farther).
    Arrive,
    /// Round the copy at that radius and height to where the pokes start.
    Circle,
    /// In (or down) to where the pokes start.
    Settle,
    /// After a disturbance: out to the ring of pokes, waiting there for the forces to come back.
    Retreat,
    /// Round the ring of pokes to where they start.
    Return,
    Taps,
    /// Round the ring of pokes, the short way, to the angle of the press (never across the copy).
    Round,
    Approach,
    Press,
    SlideDown,
    SlideUp,
    Done,
}

impl Stage {
    /// Whether the stage measures the copy (so a disturbance during it spoils the attempt).
    fn measures(self) -> bool {
        matches!(self, Stage::Taps | Stage::SlideDown | Stage::SlideUp)
    }
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
    /// Sliding samples of this stroke: all of them, and those in touch.
    stroke: (u32, u32),
    /// In-touch sliding samples of this press's strokes, for the ridges.
    strokes: Vec<StrokeSample>,
    presses: u32,
    last: Option<(u64, Vec3)>,
    /// Haptic-clock time from which the forces are whole again after the last stall or stale data.
    calm_from_us: u64,
    /// Whether this attempt measured before `calm_from_us`.
    disturbed: bool,
    /// What disturbed the haptic loop (the first event of each spell).
    disturbances: Vec<Disturbance>,
    /// Haptic-clock time the exploration began.
    began_us: u64,
    attempts: u32,
    unconfirmed: u32,
    findings: Option<Findings>,
    /// With 3-DOF proxy rendering: resting force over depth (N/m) above which a copy feels hard.
    hard_above_n_per_m: Option<f32>,
}

impl Exploration {
    /// Starts exploring a copy of `kind` at haptic-clock time `now_us`, with the stylus at `hand`
    /// (workbench frame: [`crate::bench::Haptics::stylus`]). The hand first goes out from the
    /// copy's axis and round it to where the pokes start, never across the copy: a hand that jumped
    /// straight there from the far side (where the last exploration ended) pulled the stylus through
    /// the copy, and the 3-DOF proxy, which lets go only once the way back is free, held it inside,
    /// 3 mm deep, for half the ring of pokes (a whole side of an idol read as one flat run).
    pub fn new(kind: ArtifactKind, now_us: u64, hand: Vec3) -> Self {
        let (_, r_out, ..) = ring(kind);
        let hand = if hand.is_finite() { hand } else { Vec3::new(r_out, 0.0, 0.0) };
        let out = Vec3::new(hand.x, 0.0, hand.z).try_normalize().unwrap_or(Vec3::X);
        let radius = Vec3::new(hand.x, 0.0, hand.z).length().max(r_out);
        Self {
            kind,
            stage: Stage::Arrive,
            goal: HandGoal::Line {
                from: hand,
                to: Vec3::new(0.0, hand.y, 0.0) + out * radius,
                duration_s: 0.3,
                start_us: now_us,
            },
            stage_start_us: now_us,
            stage_end_us: now_us + 350_000,
            taps_start_us: 0,
            tap_touch: vec![None; taps(kind)],
            tap_min: vec![f32::INFINITY; taps(kind)],
            tap_hold: vec![Hold::default(); taps(kind)],
            press_angle: 0.0,
            press_normal: Vec3::X,
            surface: 0.0,
            slide: (0.0, 0.0),
            stroke: (0, 0),
            strokes: Vec::with_capacity(2048),
            presses: 1,
            last: None,
            calm_from_us: 0,
            disturbed: false,
            disturbances: Vec::with_capacity(2 * ATTEMPTS as usize),
            began_us: now_us,
            attempts: 1,
            unconfirmed: 0,
            findings: None,
            hard_above_n_per_m: None,
        }
    }

    /// Judges hardness by the resting force over the depth against `threshold` (N/m) instead of the
    /// volumetric rendering's force over depth²: with 3-DOF proxy rendering the force is a spring,
    /// k × depth (see [`crate::bench::Bench::hard_above_n_per_m`]).
    pub fn judging_springs(mut self, threshold: Option<f32>) -> Self {
        self.hard_above_n_per_m = threshold;
        self
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
        // A disturbed attempt stops at once when another is allowed; the last one runs to its end.
        let disturbed = self.stage.measures() && self.disturbed && self.attempts < ATTEMPTS;
        if (now_us < self.stage_end_us && !disturbed) || self.stage == Stage::Done {
            return false;
        }
        // A first stroke that met nothing where the pokes found the surface says they went wrong there
        // (one missed notch moves the plain part into it): explore again while another attempt is
        // allowed; the last one presses deeper.
        let unconfirmed =
            self.stage == Stage::SlideUp && self.presses == 1 && self.stroke_missed() && self.attempts < ATTEMPTS;
        self.unconfirmed += u32::from(unconfirmed && !disturbed);
        let start_over = disturbed || unconfirmed;
        let (y, r_out, r_in, y_press) = ring(self.kind);
        let start = now_us + 10_000;
        let at = self.goal.sample(now_us).translation;
        let line = |from: Vec3, to: Vec3, duration_s: f32| HandGoal::Line { from, to, duration_s, start_us: start };
        let axis = Vec3::new(0.0, y_press, 0.0);
        let centre = Vec3::new(0.0, y, 0.0);
        let (next, goal, seconds) = match self.stage {
            Stage::Arrive => {
                // At the height and distance from the axis where the hand now is.
                let radius = Vec3::new(at.x, 0.0, at.z).length();
                let (round, seconds) = short_way_round(at, Vec3::new(0.0, at.y, 0.0), radius, 0.0, start);
                (Stage::Circle, round, seconds)
            }
            Stage::Circle => (Stage::Settle, line(at, Vec3::new(r_out, y, 0.0), 0.6), 1.0),
            _ if start_over => {
                // Straight out from the axis (never across the copy) to the ring, and wait there.
                self.attempts += 1;
                let out = Vec3::new(at.x, 0.0, at.z).try_normalize().unwrap_or(Vec3::X) * r_out;
                let wait = self.calm_from_us.saturating_sub(start).max(600_000) as f32 * 1e-6;
                (Stage::Retreat, line(at, centre + out, 0.5), wait)
            }
            Stage::Retreat => {
                // Round the ring, the way the pokes go, back to their first angle.
                let start_rad = (-at.z).atan2(at.x).rem_euclid(TAU);
                let turns = (1.0 - start_rad / TAU).fract();
                let round = HandGoal::Orbit { centre, radius: r_out, start_rad, period_s: 3.0, turns, start_us: start };
                (Stage::Return, round, 3.0 * turns + 0.05)
            }
            Stage::Settle | Stage::Return => {
                self.restart_taps(start);
                let n = taps(self.kind);
                let goal = HandGoal::Taps { centre, r_out, r_in, n: n as u32, tap_s: TAP_S, start_us: start };
                (Stage::Taps, goal, n as f32 * TAP_S + 0.05)
            }
            Stage::Taps => {
                self.press_angle = self.plain_angle();
                self.press_normal = Vec3::new(self.press_angle.cos(), 0.0, -self.press_angle.sin());
                let n = taps(self.kind);
                let k = ((self.press_angle / TAU * n as f32).round() as usize) % n;
                // Where the pokes there first touched (the median of the nearest, so one that went wrong
                // does not decide); where none touched, a little outside the pokes' reach.
                let touches = self.touches();
                let near = (n + k - PRESS_SPAN..=n + k + PRESS_SPAN).filter_map(|i| touches[i % n]).collect();
                self.surface = median(near).unwrap_or(r_in + 0.007);
                let (round, seconds) = short_way_round(at, centre, r_out, self.press_angle, start);
                (Stage::Round, round, seconds)
            }
            Stage::Round => (Stage::Approach, line(at, axis + self.press_normal * r_out, 0.4), 0.5),
            Stage::Approach => {
                let reach = REACH_M + DEEPER_M * (self.presses - 1) as f32;
                (Stage::Press, line(at, axis + self.press_normal * (self.surface - reach), 0.5), 0.8)
            }
            Stage::Press => {
                self.slide = (0.0, 0.0);
                self.stroke = (0, 0);
                self.strokes.clear();
                (Stage::SlideDown, line(at, at - Vec3::Y * SLIDE_M, 0.5), 0.55)
            }
            Stage::SlideDown => (Stage::SlideUp, line(at, at + Vec3::Y * SLIDE_M, 0.5), 0.55),
            Stage::SlideUp if self.stroke_missed() && self.presses < ATTEMPTS => {
                // The press met nothing: back off and press again, deeper.
                self.presses += 1;
                (Stage::Approach, line(at, axis + self.press_normal * r_out, 0.4), 0.5)
            }
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

    /// Forgets what the taps found, for a fresh start at `start_us` (each press forgets its stroke).
    fn restart_taps(&mut self, start_us: u64) {
        self.taps_start_us = start_us;
        self.tap_touch.fill(None);
        self.tap_min.fill(f32::INFINITY);
        self.tap_hold.fill(Hold::default());
        self.presses = 1;
        self.disturbed = false;
    }

    /// Whether the stroke was mostly out of touch (or never slid): it says nothing about the friction.
    fn stroke_missed(&self) -> bool {
        2 * self.stroke.1 < self.stroke.0 || self.stroke.0 == 0
    }

    fn take(&mut self, s: &ForceSample) {
        let p = s.tool_position;
        let radial = Vec3::new(p.x, 0.0, p.z).length();
        let velocity = match self.last {
            Some((t, q)) if s.t_us > t => (p - q) / ((s.t_us - t) as f32 * 1e-6),
            _ => Vec3::ZERO,
        };
        let gap_us = self.last.map_or(0, |(t, _)| s.t_us.saturating_sub(t));
        let stalled = gap_us > STALL_US;
        if stalled || s.data_age_us > STALE_US {
            // The first event of each spell, a few per exploration.
            let this_attempt = self.disturbances.iter().filter(|d| d.attempt == self.attempts).count();
            if s.t_us >= self.calm_from_us && this_attempt < MAX_DISTURBANCES {
                self.disturbances.push(Disturbance {
                    attempt: self.attempts,
                    at_s: s.t_us.saturating_sub(self.began_us) as f32 * 1e-6,
                    gap_ms: if stalled { gap_us as f32 } else { s.data_age_us as f32 } * 1e-3,
                    stale: !stalled,
                    stage: self.stage,
                });
            }
            self.calm_from_us = s.t_us + RECOVER_US;
        }
        self.disturbed |= self.stage.measures() && s.t_us < self.calm_from_us;
        self.last = Some((s.t_us, p));
        let touching = s.contact_force.length() > TOUCH_N;
        match self.stage {
            Stage::Taps => {
                let since = s.t_us.saturating_sub(self.taps_start_us) as f32 * 1e-6 / TAP_S;
                let (k, u) = (since.floor() as usize, since.fract());
                if k >= self.tap_touch.len() || s.t_us < self.taps_start_us {
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
                if velocity.y.abs() > 0.005 {
                    self.stroke.0 += 1;
                    if normal > TOUCH_N {
                        self.stroke.1 += 1;
                        self.slide.0 += -s.contact_force.y * velocity.y.signum();
                        self.slide.1 += normal;
                        self.strokes.push(StrokeSample {
                            height: p.y,
                            along: s.contact_force.y,
                            normal,
                            up: velocity.y > 0.0,
                        });
                    }
                }
            }
            _ => {}
        }
    }

    /// Which pokes were missed: the stylus met nothing, yet did not get even halfway in (or nothing was
    /// sampled while it should have been in), or it met something where no copy reaches: no copy is wider
    /// than its kind's look, so a first touch lies within the look's radius and the stylus's (2 mm spare).
    /// Nothing on an idol stands out from its body (its features are notches), so there a touch more than
    /// [`SPIKE_M`] farther out than the median touch is missed too.
    fn missed(&self) -> impl Iterator<Item = bool> + '_ {
        let (_, r_out, r_in, _) = ring(self.kind);
        let halfway = 0.5 * (r_out + r_in);
        let mut reach = 0.5 * artifact::look(self.kind).size_m[0] + 0.5 * TOOL_DIAMETER_M + 0.002;
        if self.kind == ArtifactKind::Idol {
            let within = self.tap_touch.iter().flatten().copied().filter(|r| *r <= reach).collect();
            reach = reach.min(median(within).map_or(f32::INFINITY, |body| body + SPIKE_M));
        }
        self.tap_touch.iter().zip(&self.tap_min).map(move |(touch, min)| match touch {
            Some(r) => *r > reach,
            None => !min.is_finite() || *min >= halfway,
        })
    }

    /// Where each poke first touched, but for the missed ones.
    fn touches(&self) -> Vec<Option<f32>> {
        self.tap_touch.iter().zip(self.missed()).map(|(touch, missed)| touch.filter(|_| !missed)).collect()
    }

    /// The profile of the taps: where each first touched, or how deep it got; a missed poke reads as the
    /// one before it (the last one before it that was not missed).
    fn profile(&self) -> Vec<f32> {
        let raw: Vec<Option<f32>> = self
            .tap_touch
            .iter()
            .zip(&self.tap_min)
            .zip(self.missed())
            .map(|((touch, min), missed)| (!missed).then(|| touch.unwrap_or(*min)))
            .collect();
        let Some(last) = raw.iter().rev().flatten().next() else { return vec![0.0; raw.len()] };
        raw.iter()
            .scan(*last, |before, r| {
                *before = r.unwrap_or(*before);
                Some(*before)
            })
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
        TAU * pick as f32 / profile.len() as f32
    }

    fn conclude(&self) -> Findings {
        let profile = self.profile();
        let feature_count = match self.kind {
            ArtifactKind::Crown | ArtifactKind::Amphora => artifact::count_high_runs(&profile),
            ArtifactKind::Idol => count_notches(&profile),
        };
        // Stiffness: the median, over the pokes that met a plain part, of the force at rest over the depth
        // since first touch. Plain parts: the amphora's belly (the lower touches; its ridges are narrow
        // and give way), the idol's body and the crown's points (the higher touches).
        let touches = self.touches();
        let touched: Vec<f32> = touches.iter().flatten().copied().collect();
        let (lo, hi) = touched.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &r| (a.min(r), b.max(r)));
        let mid = 0.5 * (lo + hi);
        let plain = |r: f32| if self.kind == ArtifactKind::Amphora { r <= mid } else { r >= mid };
        let rests: Vec<(f32, f32)> = touches
            .iter()
            .zip(&self.tap_hold)
            .filter_map(|(touch, hold)| {
                let (touch, (at, force)) = ((*touch)?, hold.mean()?);
                (plain(touch) && touch - at > 2e-4 && force > TOUCH_N).then_some((touch - at, force))
            })
            .collect();
        let stiffness_n_per_m = median(rests.iter().map(|(d, f)| f / d).collect()).unwrap_or(0.0);
        let pressure_n_per_m2 = median(rests.iter().map(|(d, f)| f / (d * d)).collect()).unwrap_or(0.0);
        let friction = if self.slide.1 > 0.0 { self.slide.0 / self.slide.1 } else { 0.0 };
        let ridges = strongest_repeat(&self.strokes);
        let rough = ridges.is_some_and(|(_, strength)| strength > RIDGES_ABOVE) && friction > ROUGH_ABOVE;
        let hard = match self.hard_above_n_per_m {
            Some(threshold) => stiffness_n_per_m > threshold,
            None => pressure_n_per_m2 > HARD_ABOVE_N_PER_M2,
        };
        let material = match (hard, rough) {
            (true, false) => MaterialClass::HardSmooth,
            (true, true) => MaterialClass::HardRough,
            (false, false) => MaterialClass::SoftSmooth,
            (false, true) => MaterialClass::SoftRough,
        };
        Findings {
            profile,
            feature_count,
            stiffness_n_per_m,
            pressure_n_per_m2,
            friction,
            ridges,
            material,
            attempts: self.attempts,
            unconfirmed: self.unconfirmed,
            presses: self.presses,
            stroke_contact: if self.stroke.0 > 0 { self.stroke.1 as f32 / self.stroke.0 as f32 } else { 0.0 },
            disturbed: self.disturbed,
            disturbances: self.disturbances.clone(),
        }
    }
}

/// Round the copy's axis from `at`'s angle to `to_rad`, the short way, on a circle of `radius` about
/// `centre` (one turn in 3 s), starting at `start_us`; and how long the stage lasts, s.
fn short_way_round(at: Vec3, centre: Vec3, radius: f32, to_rad: f32, start_us: u64) -> (HandGoal, f32) {
    let start_rad = (-at.z).atan2(at.x);
    let turns = ((to_rad - start_rad) / TAU + 0.5).rem_euclid(1.0) - 0.5;
    (HandGoal::Orbit { centre, radius, start_rad, period_s: 3.0, turns, start_us }, 3.0 * turns.abs() + 0.05)
}

/// Places `copy` on `bench` (the client's running loop, or the same loop in lockstep: see
/// [`crate::touch_bench`]) and explores it; gives up after a minute for the build and a minute of haptic
/// time for each exploration. Used by the tests and the `feel_copies` example; the client runs the same
/// steps from its systems.
pub fn feel(
    bench: &mut impl TouchBench,
    copy: &heist_shared::protocol::WorkbenchCopy,
    kind: ArtifactKind,
) -> Result<Findings, String> {
    /// The client's frame, about: how often the bot looks at what the hand felt, ms.
    const FRAME_MS: u64 = 8;
    bench.place_and_wait(copy)?;
    let mut ex = Exploration::new(kind, bench.now_us(), bench.stylus()).judging_springs(bench.hard_above_n_per_m());
    let map = bench.map();
    bench.steer(to_device(&map, ex.goal()))?;
    let deadline_us = bench.now_us() + 60_000_000 * u64::from(ATTEMPTS);
    while !ex.done() {
        if bench.now_us() > deadline_us {
            return Err(format!("the exploration did not end within {ATTEMPTS} minutes"));
        }
        bench.wait(FRAME_MS);
        if ex.step(bench.now_us(), bench.samples()) {
            bench.steer(to_device(&map, ex.goal()))?;
        }
    }
    ex.findings().cloned().ok_or_else(|| "no findings".into())
}

#[cfg(test)]
mod tests;
