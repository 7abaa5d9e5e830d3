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

use std::f32::consts::TAU;

use glam::Vec3;
use haptic_rig::ForceSample;
use heist_shared::artifact::{self, ArtifactKind, Briefing, MaterialClass};

use crate::device::{HandGoal, to_device};
use crate::haptics::TOOL_DIAMETER_M;
use crate::touch_bench::TouchBench;

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

/// Contact force that counts as touching, N.
const TOUCH_N: f32 = 0.05;
/// How far past the surface the hand reaches when pressing to stroke (lightly: the stylus stays in the
/// skin, where the sphere packing is even), m.
const REACH_M: f32 = 0.003;
/// Length of the strokes down and up, m.
const SLIDE_M: f32 = 0.012;
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

/// One in-touch sample of a stroke: the stylus's height, the contact force along the stroke and into
/// the copy, and which way it went.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StrokeSample {
    height: f32,
    along: f32,
    normal: f32,
    up: bool,
}

/// Shortest and longest ridge spacing looked for, m: the stroke must cross at least three.
const RIDGE_SPACINGS_M: (f32, f32) = (0.0015, SLIDE_M / 3.0);
/// A push along the stroke that repeats with the stylus's height, this strong against the normal force
/// (its Fourier amplitude over each way of the stroke), means ridges. Ribbed copies gave 0.25–0.48 and
/// the packing's bumps on smooth ones at most 0.12 through the proxy, 0.24 once through the volumetric
/// rendering (seeds 21–24, docs/phantom-client.md) before the copy had a surface grid, at most 0.02 since
/// (seeds 3, 5, 11).
pub const RIDGES_ABOVE: f32 = 0.18;

/// The spacing at which the push along the stroke (less its mean on each way: the friction) repeats
/// most strongly with the stylus's height on each way, and that strength over the mean normal force;
/// None for fewer than 64 samples in touch.
fn strongest_repeat(strokes: &[StrokeSample]) -> Option<(f32, f32)> {
    if strokes.len() < 64 {
        return None;
    }
    let mean = |up: bool| {
        let (sum, n) = strokes.iter().filter(|s| s.up == up).fold((0.0, 0u32), |(a, n), s| (a + s.along, n + 1));
        if n > 0 { sum / n as f32 } else { 0.0 }
    };
    let (mean_up, mean_down) = (mean(true), mean(false));
    let normal = strokes.iter().map(|s| s.normal).sum::<f32>() / strokes.len() as f32;
    // Each way on its own: the stylus lags the hand by up to the friction cone, one way down and the
    // other way up, so the two ways' repeats can be out of phase (by half a ridge on a soft rough copy).
    let strength = |spacing: f32| {
        let (mut amplitude, mut total) = (0.0f32, 0.0f32);
        for up in [false, true] {
            let (mut c, mut s, mut travel) = (0.0f32, 0.0f32, 0.0f32);
            for w in strokes.windows(2).filter(|w| w[0].up == up && w[1].up == up) {
                let (a, b) = (w[0], w[1]);
                let dy = (b.height - a.height).abs();
                if dy > 0.001 {
                    continue; // a gap in touch
                }
                let push = b.along - if up { mean_up } else { mean_down };
                let phase = TAU * b.height / spacing;
                c += push * phase.cos() * dy;
                s += push * phase.sin() * dy;
                travel += dy;
            }
            if travel > 0.0 {
                amplitude += 2.0 * c.hypot(s);
                total += travel;
            }
        }
        if total > 0.0 { amplitude / total / normal.max(TOUCH_N) } else { 0.0 }
    };
    let (lo, hi) = RIDGE_SPACINGS_M;
    (0..=64)
        .map(|i| lo * (hi / lo).powf(i as f32 / 64.0))
        .map(|spacing| (spacing, strength(spacing)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
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

/// The median of `v` (the upper one of an even count), if any.
fn median(mut v: Vec<f32>) -> Option<f32> {
    v.sort_by(f32::total_cmp);
    v.get(v.len() / 2).copied()
}

/// Notches in an idol's circular profile of [`IDOL_TAPS`] pokes, measured from its body (the median:
/// notches are under half the circle) rather than from its widest touch. A notch spans four pokes or
/// more; a single poke that touched too early or too late (seen 3.6 mm below the body and 2 mm above,
/// between pokes that read the body) is no notch, so each poke reads as the median of itself and its two
/// neighbours. A notch starts 30 % of the way from the body down to the deepest poke and ends 15 % of the
/// way (hysteresis); a profile varying less than [`artifact::MIN_FEATURE_SIZE_M`] has none.
fn count_notches(profile: &[f32]) -> u32 {
    let n = profile.len();
    let profile: Vec<f32> = (0..n)
        .map(|i| median(vec![profile[(i + n - 1) % n], profile[i], profile[(i + 1) % n]]).unwrap_or(0.0))
        .collect();
    let (Some(body), Some(start)) =
        (median(profile.clone()), profile.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i))
    else {
        return 0;
    };
    let deepest = profile.iter().copied().fold(f32::INFINITY, f32::min);
    if body - deepest < artifact::MIN_FEATURE_SIZE_M {
        return 0;
    }
    let (enter, leave) = (body - 0.3 * (body - deepest), body - 0.15 * (body - deepest));
    let (mut inside, mut notches) = (false, 0);
    // Starting at the widest poke, the circle begins and ends outside a notch: none is cut in two.
    for i in 0..n {
        let r = profile[(start + i) % n];
        if !inside && r < enter {
            (inside, notches) = (true, notches + 1);
        } else if inside && r > leave {
            inside = false;
        }
    }
    notches
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Radius of the frictionless vertical cylinder the tests' idol is, m: the look's.
    fn body_radius() -> f32 {
        0.5 * artifact::look(ArtifactKind::Idol).size_m[0]
    }

    /// Depth of the tests' idol's one notch, 5 mm deep, within 0.55 rad of π (17 of its 96 pokes), m.
    fn notch(p: Vec3) -> f32 {
        let angle = (-p.z).atan2(p.x).rem_euclid(TAU);
        if (angle - std::f32::consts::PI).abs() < 0.55 { 0.005 } else { 0.0 }
    }

    /// Where the tests' hand starts: above where the pokes start.
    fn start() -> Vec3 {
        let (y, r_out, ..) = ring(ArtifactKind::Idol);
        Vec3::new(r_out, y + 0.05, 0.0)
    }

    /// Runs an exploration of an idol (a cylinder of [`body_radius`] with a [`notch`], 200 N/m) on a hand that follows
    /// its goal exactly, with frames every 8 ms; `tick(t_us)` says whether the haptic loop ticks at
    /// `t_us` and how old its contact data is. Returns the findings and the stages seen, with the time
    /// each began.
    fn run(tick: impl FnMut(u64) -> Option<u32>) -> (Findings, Vec<(Stage, u64)>) {
        let (findings, stages, _) = run_held(tick, |_, _| None);
        (findings, stages)
    }

    /// [`run`], with the tool held at `held(exploration, t_us)` instead of the goal when that says so;
    /// also returns the exploration.
    fn run_held(
        tick: impl FnMut(u64) -> Option<u32>,
        held: impl Fn(&Exploration, u64) -> Option<Vec3>,
    ) -> (Findings, Vec<(Stage, u64)>, Exploration) {
        run_from(start(), tick, held)
    }

    /// [`run_held`] with the hand starting at `hand`.
    fn run_from(
        hand: Vec3,
        mut tick: impl FnMut(u64) -> Option<u32>,
        held: impl Fn(&Exploration, u64) -> Option<Vec3>,
    ) -> (Findings, Vec<(Stage, u64)>, Exploration) {
        let mut ex = Exploration::new(ArtifactKind::Idol, 0, hand);
        let mut stages = vec![(ex.stage, 0)];
        let mut samples = Vec::new();
        for frame in 1..40_000u64 {
            let now = frame * 8_000;
            samples.clear();
            for t_us in (now - 8_000..now).step_by(1_000) {
                if let Some(data_age_us) = tick(t_us) {
                    let tool_position = held(&ex, t_us).unwrap_or(ex.goal().sample(t_us).translation);
                    let out = Vec3::new(tool_position.x, 0.0, tool_position.z);
                    let depth = (body_radius() - notch(out) - out.length()).max(0.0);
                    let contact_force = out.normalize_or_zero() * 200.0 * depth;
                    samples.push(ForceSample {
                        t_us,
                        tool_position,
                        contact_force,
                        data_age_us,
                        ..ForceSample::default()
                    });
                }
            }
            if ex.step(now, &samples) {
                stages.push((ex.stage, ex.stage_start_us));
                let (_, r_out, ..) = ring(ArtifactKind::Idol);
                if matches!(ex.stage, Stage::Return | Stage::Round) {
                    for dt in (0..3_000_000).step_by(100_000) {
                        let p = ex.goal().sample(ex.stage_start_us + dt).translation;
                        assert!((Vec3::new(p.x, 0.0, p.z).length() - r_out).abs() < 1e-4, "round the ring");
                    }
                }
                if ex.stage == Stage::Round {
                    // It ends at the press's angle: the approach then only moves along the axis.
                    let end = ex.goal().sample(ex.stage_end_us).translation;
                    let angle = (-end.z).atan2(end.x).rem_euclid(TAU);
                    let off = (angle - ex.press_angle.rem_euclid(TAU) + 3.0 * std::f32::consts::PI).rem_euclid(TAU)
                        - std::f32::consts::PI;
                    assert!(off.abs() < 1e-3, "ends {off} rad from the press's angle");
                }
            }
            if let Some(f) = ex.findings() {
                return (f.clone(), stages, ex);
            }
        }
        panic!("the exploration never ended: {stages:?}");
    }

    #[test]
    fn an_undisturbed_exploration_takes_one_attempt_and_one_press() {
        let (findings, stages) = run(|_| Some(1_000));
        assert_eq!((findings.attempts, findings.disturbed, findings.presses), (1, false, 1), "{stages:?}");
        assert!(!stages.iter().any(|(s, _)| *s == Stage::Retreat), "{stages:?}");
        assert!(stages.iter().any(|(s, _)| *s == Stage::Round), "goes round the ring to press: {stages:?}");
        assert!(findings.stroke_contact > 0.9, "{findings:?}");
        let r = body_radius();
        let (body, notch) = (r - 0.001..r, r - 0.006..r - 0.005);
        let at = |k: usize| {
            let phi = TAU * k as f32 / IDOL_TAPS as f32;
            Vec3::new(phi.cos(), 0.0, -phi.sin())
        };
        let felt = |k: usize| if super::tests::notch(at(k)) > 0.0 { notch.clone() } else { body.clone() };
        assert!(findings.profile.iter().enumerate().all(|(k, p)| felt(k).contains(p)), "{findings:?}");
        assert_eq!(findings.feature_count, 1, "{findings:?}");
        assert!(findings.stiffness_n_per_m > 150.0 && findings.stiffness_n_per_m < 250.0, "{findings:?}");
    }

    #[test]
    fn the_hand_goes_round_the_copy_to_the_first_poke_never_across_it() {
        let (y, r_out, ..) = ring(ArtifactKind::Idol);
        let radial = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
        // Where the last exploration ended: out from a press on the far side, a little lower.
        let far = Vec3::new(-(r_out + 0.02), y - 0.01, 0.003);
        let nearest = std::cell::Cell::new(f32::INFINITY);
        let first = std::cell::Cell::new(None);
        let held = |ex: &Exploration, t| {
            if matches!(ex.stage, Stage::Arrive | Stage::Circle | Stage::Settle) {
                let p = ex.goal.sample(t).translation;
                first.set(first.get().or(Some(p)));
                nearest.set(nearest.get().min(radial(p)));
            }
            None
        };
        let (findings, stages, _) = run_from(far, |_| Some(1_000), held);
        assert!(first.get().is_some_and(|p| p.distance(far) < 1e-4), "starts where the hand is: {:?}", first.get());
        assert!(nearest.get() > r_out - 1e-4, "{} m from the axis, the ring is at {r_out} m", nearest.get());
        let order: Vec<Stage> = stages.iter().map(|(s, _)| *s).take(4).collect();
        assert_eq!(order, [Stage::Arrive, Stage::Circle, Stage::Settle, Stage::Taps]);
        assert_eq!((findings.feature_count, findings.attempts), (1, 1), "{findings:?}");
        // A hand inside the ring goes straight out first.
        let near = Vec3::new(0.0, y, 0.02);
        let ex = Exploration::new(ArtifactKind::Idol, 0, near);
        let out = ex.goal.sample(1_000_000).translation;
        assert!((radial(out) - r_out).abs() < 1e-5 && out.x.abs() < 1e-6 && out.y == y, "{out:?}");
    }

    #[test]
    fn a_first_stroke_that_met_nothing_explores_again() {
        let (_, r_out, ..) = ring(ArtifactKind::Idol);
        // The stylus stays out through the first exploration's stroke.
        let held = |ex: &Exploration, _| {
            (matches!(ex.stage, Stage::SlideDown | Stage::SlideUp) && ex.attempts == 1)
                .then_some(Vec3::new(r_out, 0.0, 0.0))
        };
        let (findings, stages, _) = run_held(|_| Some(1_000), held);
        assert_eq!((findings.attempts, findings.unconfirmed, findings.presses), (2, 1, 1), "{stages:?}");
        assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Taps).count(), 2, "poked again: {stages:?}");
        assert_eq!(findings.feature_count, 1);
        assert!(findings.stroke_contact > 0.9, "the second stroke touched: {findings:?}");
        assert!(findings.describe().contains("1 with a first stroke that met nothing"), "{}", findings.describe());
    }

    #[test]
    fn on_the_last_exploration_a_stroke_that_met_nothing_is_pressed_again_deeper() {
        let (_, r_out, ..) = ring(ArtifactKind::Idol);
        let radial = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
        // The stylus stays out through each exploration's first stroke; how deep each press of the last
        // exploration reaches for is noted.
        let deepest = std::cell::RefCell::new([f32::INFINITY; ATTEMPTS as usize]);
        let held = |ex: &Exploration, t| {
            if ex.stage == Stage::Press && ex.attempts == ATTEMPTS {
                let d = &mut deepest.borrow_mut()[ex.presses as usize - 1];
                *d = d.min(radial(ex.goal.sample(t).translation));
            }
            (matches!(ex.stage, Stage::SlideDown | Stage::SlideUp) && ex.presses == 1)
                .then_some(Vec3::new(r_out, 0.0, 0.0))
        };
        let (findings, stages, ex) = run_held(|_| Some(1_000), held);
        let deepest = deepest.into_inner();
        assert!((deepest[0] - (ex.surface - REACH_M)).abs() < 1e-4, "{deepest:?}");
        assert!((deepest[0] - deepest[1] - DEEPER_M).abs() < 1e-4, "the second press reaches 2 mm deeper: {deepest:?}");
        assert_eq!((findings.attempts, findings.unconfirmed, findings.presses), (ATTEMPTS, ATTEMPTS - 1, 2));
        assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Press).count(), ATTEMPTS as usize + 1, "{stages:?}");
        assert!(findings.stroke_contact > 0.9, "the second stroke touched: {findings:?}");
        assert!(findings.describe().contains("2 presses"), "{}", findings.describe());
        let press = ex.goal.sample(u64::MAX);
        assert!(radial(press.translation) > r_out, "backed out at the end: {press:?}");
        assert!((ex.surface - body_radius()).abs() < 0.001, "the surface where the cylinder is: {}", ex.surface);
        // A stroke that never meets anything ends after the last press, friction unknown (0).
        let never = |ex: &Exploration, _| {
            matches!(ex.stage, Stage::SlideDown | Stage::SlideUp).then_some(Vec3::new(r_out, 0.0, 0.0))
        };
        let (findings, stages, _) = run_held(|_| Some(1_000), never);
        assert_eq!((findings.presses, findings.stroke_contact, findings.friction), (ATTEMPTS, 0.0, 0.0), "{stages:?}");
    }

    #[test]
    fn a_missed_poke_where_the_press_goes_takes_the_surface_from_the_poke_before() {
        let (_, r_out, ..) = ring(ArtifactKind::Idol);
        // The press goes to the first poke's angle, opposite the notch; the stylus stays out through
        // that poke.
        let poke = |ex: &Exploration| ex.taps_start_us..ex.taps_start_us + (TAP_S * 1e6) as u64;
        let held = |ex: &Exploration, t| {
            (ex.stage == Stage::Taps && poke(ex).contains(&t)).then_some(Vec3::new(r_out, 0.0, 0.0))
        };
        let (findings, _, ex) = run_held(|_| Some(1_000), held);
        assert!(ex.touches()[0].is_none() && ex.press_angle == 0.0, "{findings:?}");
        assert!((ex.surface - body_radius()).abs() < 0.001, "the surface where the cylinder is: {}", ex.surface);
        assert_eq!(findings.presses, 1);
    }

    #[test]
    fn a_stall_during_the_taps_starts_over_once_the_forces_are_whole_again() {
        // The process is not scheduled for 1.5 s, 5 s in (during the taps).
        let (findings, stages) = run(|t| (!(5_000_000..6_500_000).contains(&t)).then_some(1_000));
        assert_eq!((findings.attempts, findings.disturbed), (2, false), "{stages:?}");
        let at = |stage| stages.iter().filter(|(s, _)| *s == stage).map(|(_, t)| *t).collect::<Vec<_>>();
        let retreat = at(Stage::Retreat);
        assert_eq!(retreat.len(), 1, "{stages:?}");
        assert!(retreat[0] < 6_600_000, "the disturbed attempt stops at once: {stages:?}");
        let taps = at(Stage::Taps);
        assert_eq!(taps.len(), 2, "{stages:?}");
        assert!(taps[1] >= 6_500_000 + RECOVER_US, "the new taps wait for the forces: {stages:?}");
        assert_eq!(at(Stage::Return).len(), 1, "{stages:?}");
        // The log says what disturbed it, when and where.
        assert_eq!(findings.disturbances.len(), 1, "{:?}", findings.disturbances);
        let d = findings.disturbances[0];
        assert!((d.attempt, d.stale, d.stage) == (1, false, Stage::Taps) && (d.gap_ms - 1_501.0).abs() < 10.0, "{d:?}");
        assert!(
            findings.describe().contains("a stall of 1501 ms at 6.5 s (taps, exploration 1)"),
            "{}",
            findings.describe()
        );
    }

    #[test]
    fn a_poke_the_stylus_did_not_follow_reads_as_the_one_before() {
        let (_, r_out, ..) = ring(ArtifactKind::Idol);
        // The stylus stays out through the eighth poke.
        let poke = |ex: &Exploration| {
            ex.taps_start_us + (7.0 * TAP_S * 1e6) as u64..ex.taps_start_us + (8.0 * TAP_S * 1e6) as u64
        };
        let held = |ex: &Exploration, t| {
            (ex.stage == Stage::Taps && poke(ex).contains(&t)).then_some(Vec3::new(r_out, 0.0, 0.0))
        };
        let (findings, stages, _) = run_held(|_| Some(1_000), held);
        assert_eq!(stages.iter().filter(|(s, _)| *s == Stage::Taps).count(), 1, "{stages:?}");
        assert_eq!((findings.attempts, findings.disturbed), (1, false), "{stages:?}");
        assert_eq!(findings.profile[7], findings.profile[6], "{:?}", findings.profile);
        assert!(findings.profile[7] < r_out - 0.01, "{:?}", findings.profile);
        // A missed poke reads as the one before it, the first as the last.
        let mut ex = Exploration::new(ArtifactKind::Idol, 0, start());
        ex.tap_min.fill(0.02);
        ex.tap_min[7] = r_out;
        ex.tap_min[3] = 0.025;
        assert!(ex.missed().enumerate().all(|(k, missed)| missed == (k == 7)));
        let profile = ex.profile();
        assert_eq!((profile[3], profile[7], profile[8]), (0.025, 0.02, 0.02));
        ex.tap_min[0] = r_out;
        assert_eq!(ex.profile()[0], 0.02, "the first poke reads as the last one");
        let reach = 0.5 * artifact::look(ArtifactKind::Idol).size_m[0] + 0.5 * TOOL_DIAMETER_M + 0.002;
        ex.tap_touch[5] = Some(reach + 0.001);
        ex.tap_touch[6] = Some(reach - 0.001);
        let missed: Vec<usize> = ex.missed().enumerate().filter_map(|(k, m)| m.then_some(k)).collect();
        assert_eq!(missed, [0, 5, 7], "a touch where no copy reaches is missed too");
        assert_eq!((ex.touches()[5], ex.touches()[6]), (None, Some(reach - 0.001)), "never rested on");
        assert!(r_out - 0.005 > reach + 0.001, "closer than where the poke starts");
    }

    #[test]
    fn stale_contact_data_all_along_ends_after_the_last_attempt_marked_disturbed() {
        let (findings, stages) = run(|_| Some(STALE_US + 1));
        assert_eq!((findings.attempts, findings.disturbed), (ATTEMPTS, true), "{stages:?}");
        assert!(findings.describe().contains("disturbed in all 3 explorations"), "{}", findings.describe());
    }

    #[test]
    fn touches_where_nothing_is_on_an_idol_are_missed_and_the_press_goes_to_its_body() {
        // Profiles (mm) of the real idol of seed 10's heist, felt with 48 pokes by the feel_copies
        // example, which read 3, 3, 1 and 3 notches of its 4: touches where nothing is (40.3 mm, 44.4 mm),
        // and a narrow notch read shallow (pokes 42–44; 30–32 in the last: hence 96 pokes for an idol).
        let felt = [
            "36.8 37.0 36.2 36.6 37.1 36.2 31.9 29.0 33.2 35.6 35.4 35.4 35.4 35.8 35.8 36.1 35.5 36.4 33.8 29.4 30.5 36.6 \
             37.0 35.6 37.0 36.8 36.8 37.2 37.2 35.8 33.4 28.8 34.0 36.0 36.2 35.9 36.2 36.2 36.6 36.8 36.5 36.1 34.4 34.4 \
             32.2 37.0 37.1 37.1",
            "36.6 36.8 35.8 36.6 36.5 36.1 31.3 29.0 33.2 35.6 35.1 35.2 35.6 35.6 35.8 36.1 35.3 36.2 33.6 29.3 30.4 36.6 \
             37.1 35.7 36.9 36.7 36.7 36.7 36.9 36.4 33.4 28.8 34.0 36.2 35.9 35.8 36.3 36.4 40.3 36.8 36.5 36.0 34.4 29.7 \
             32.3 37.0 37.2 37.0",
            "36.5 37.1 36.6 36.6 37.1 36.1 31.9 29.0 33.2 35.6 35.4 35.6 35.6 35.8 35.8 36.1 35.6 36.4 33.8 29.4 30.6 36.7 \
             37.3 35.7 37.1 36.8 36.8 37.1 37.1 36.3 33.5 28.9 34.1 36.1 44.4 35.9 36.3 36.3 36.5 36.9 36.5 36.2 34.4 29.6 \
             32.3 36.9 37.2 37.0",
            "36.6 37.4 36.2 36.6 37.0 36.2 31.9 29.0 32.8 35.6 35.4 35.7 35.4 34.9 35.6 36.2 35.4 36.3 33.1 29.4 30.5 36.2 \
             37.4 35.6 37.2 36.8 36.8 37.2 37.1 36.4 33.5 33.5 34.2 36.2 36.4 35.9 36.4 36.4 36.8 36.6 36.2 36.3 34.3 29.7 \
             32.2 37.0 37.1 37.1",
        ];
        for (i, profile) in felt.iter().enumerate() {
            let mut ex = Exploration::new(ArtifactKind::Idol, 0, start());
            let mm: Vec<f32> = profile.split_whitespace().map(|v| v.parse::<f32>().unwrap() * 1e-3).collect();
            assert_eq!(mm.len(), 48);
            (ex.tap_touch, ex.tap_min) = (vec![None; 48], vec![f32::INFINITY; 48]);
            for (touch, r) in ex.tap_touch.iter_mut().zip(mm) {
                *touch = Some(r);
            }
            let spikes: Vec<usize> = ex.missed().enumerate().filter_map(|(k, m)| m.then_some(k)).collect();
            assert_eq!(spikes, [vec![], vec![38], vec![34], vec![]][i], "profile {i}");
            // The press goes to the body, between notches.
            let k = (ex.plain_angle() / TAU * 48.0).round() as usize % 48;
            assert!(ex.profile()[k] > 0.035, "profile {i}: poke {k}");
        }
    }

    #[test]
    fn notches_are_counted_from_the_body_and_a_lone_poke_off_it_is_none() {
        // Four V notches read 4–7 pokes deep, one read shallow (its bottom between two pokes), on a body
        // of 36 ± 0.6 mm with one poke 3.6 mm in and one 2 mm out, as felt on seed 10's idol.
        let mut mm: Vec<f32> = (0..IDOL_TAPS).map(|k| if k % 2 == 0 { 36.6 } else { 35.4 }).collect();
        for (start, depths) in [
            (10, &[1.0, 3.0, 5.0, 7.2, 5.0, 3.0, 1.0][..]),
            (34, &[1.5, 4.0, 6.8, 4.0, 1.5][..]),
            (58, &[1.0, 2.0, 2.7, 2.7, 2.0, 1.0][..]),
            (80, &[2.0, 5.0, 7.0, 5.0, 2.0][..]),
        ] {
            for (k, d) in depths.iter().enumerate() {
                mm[start + k] = 36.0 - d;
            }
        }
        mm[25] = 32.4;
        mm[70] = 38.0;
        let profile: Vec<f32> = mm.iter().map(|v| v * 1e-3).collect();
        assert_eq!(count_notches(&profile), 4, "{mm:?}");
        let whole_range = artifact::count_high_runs(&profile.iter().map(|r| -r).collect::<Vec<_>>());
        assert_eq!(whole_range, 3, "35 % of the whole range misses the shallow notch");
        assert_eq!(count_notches(&[0.03; 12]), 0, "a round body has none");
    }

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

    /// A stroke 12 mm down and back up at 1 N against the copy, with friction `mu` and a push along it of
    /// `ridge` N repeating every `spacing` m, plus `bump` N of push at the packing's 1.1 mm.
    fn strokes(mu: f32, ridge: f32, spacing: f32, bump: f32) -> Vec<StrokeSample> {
        let mut out = Vec::new();
        for (up, from, to) in [(false, 0.0, -SLIDE_M), (true, -SLIDE_M, 0.0)] {
            for i in 0..500 {
                let height: f32 = from + (to - from) * i as f32 / 500.0;
                let friction = if up { -mu } else { mu };
                let along =
                    friction + ridge * (TAU * height / spacing).sin() + bump * (TAU * height / 0.0011 + 0.3).sin();
                out.push(StrokeSample { height, along, normal: 1.0, up });
            }
        }
        out
    }

    #[test]
    fn ridges_are_found_at_their_spacing_whatever_the_friction() {
        for mu in [0.1, 0.6] {
            let (spacing, strength) = strongest_repeat(&strokes(mu, 0.3, 0.003, 0.05)).expect("stroked");
            assert!(
                (spacing - 0.003).abs() < 0.0003 && (strength - 0.3).abs() < 0.05,
                "mu {mu}: {spacing} m, {strength}"
            );
        }
        let (spacing, _) = strongest_repeat(&strokes(0.3, 0.3, 0.002, 0.0)).expect("finer ribs");
        assert!((spacing - 0.002).abs() < 0.0002, "{spacing}");
        // The stylus lagging the hand half a ridge one way and not the other (a soft, rough copy): the
        // two ways' repeats are out of phase, and each still counts.
        let lagged: Vec<StrokeSample> = strokes(0.6, 0.3, 0.003, 0.0)
            .into_iter()
            .map(|s| if s.up { StrokeSample { along: -0.6 - (s.along + 0.6), ..s } } else { s })
            .collect();
        let (spacing, strength) = strongest_repeat(&lagged).expect("stroked");
        assert!((spacing - 0.003).abs() < 0.0003 && strength > 0.25, "{spacing} m, {strength}");
    }

    #[test]
    fn friction_and_the_packings_bumps_alone_are_no_ridges() {
        let weak = |s: &[StrokeSample]| strongest_repeat(s).is_some_and(|(_, strength)| strength < RIDGES_ABOVE);
        assert!(weak(&strokes(0.6, 0.0, 0.003, 0.05)) && weak(&strokes(0.1, 0.0, 0.003, 0.0)));
        // A stroke that barely touched says nothing.
        assert_eq!(strongest_repeat(&strokes(0.1, 0.3, 0.003, 0.0)[..40]), None);
    }
}
