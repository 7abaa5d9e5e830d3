//! What Phantom hears when he asks: the status line, event announcements and the lobby menu, as
//! plain sentences (numbers in words where a listener would say them).
//!
//! You need this module to change a spoken sentence. Everything here is pure: game state in, text out.

use glam::Vec2;
use heist_shared::artifact::{ArtifactKind, number_in_words};
use heist_shared::protocol::{
    GameEvent, GuardAlert, GuardView, LossReason, Phase, RadioAbout, SessionView, VerdictOutcome, WarningKind,
};

/// The lobby menu, read item by item (up/down moves, Enter chooses).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MenuItem {
    /// Tell the server Phantom is ready.
    Ready,
    /// Hear the briefing.
    Briefing,
    /// Hear the status.
    Status,
    /// Open the settings menu.
    Settings,
    /// Hear the keys.
    Help,
}

impl MenuItem {
    /// The items in order.
    pub const ALL: [MenuItem; 5] =
        [MenuItem::Ready, MenuItem::Briefing, MenuItem::Status, MenuItem::Settings, MenuItem::Help];

    /// What is said when the item is focused.
    pub fn label(self) -> &'static str {
        match self {
            MenuItem::Ready => "Ready. Press Enter when you are ready to start the heist.",
            MenuItem::Briefing => "Briefing. Press Enter to hear what the real pieces feel like.",
            MenuItem::Status => "Status. Press Enter to hear the time, the targets and the guards.",
            MenuItem::Settings => "Settings. Press Enter for speech, volumes, sound placement and the talk key.",
            MenuItem::Help => "Keys. Press Enter to hear the keys.",
        }
    }
}

/// The keys, spoken; `talk` names the push-to-talk key.
pub fn help(talk: &str) -> String {
    format!(
        "Keys: Y, the copy is real. N, it is fake. S, status. B, briefing. R, repeat the last message. \
H, tell Vive to hide. G, tell Vive to go. C, tell Vive to come back. Hold {talk} to talk to Vive on the walkie-talkie; \
typed in the terminal, talk starts and over ends. O, settings. After a heist, Enter asks for another round. \
Q leaves the session. Arrow keys, page up and page down move your hand; or use your device and its buttons: \
first button real, second button fake, third button talk."
    )
}

/// "two minutes and five seconds".
pub fn duration_words(seconds: f32) -> String {
    let s = seconds.max(0.0).round() as u32;
    let (m, s) = (s / 60, s % 60);
    let unit = |n: u32, one: &str| format!("{} {one}{}", number_in_words(n), if n == 1 { "" } else { "s" });
    match (m, s) {
        (0, s) => unit(s, "second"),
        (m, 0) => unit(m, "minute"),
        (m, s) => format!("{} and {}", unit(m, "minute"), unit(s, "second")),
    }
}

/// "north-east" for a floor offset (+y is north).
pub fn compass(d: Vec2) -> &'static str {
    const NAMES: [&str; 8] = ["east", "north-east", "north", "north-west", "west", "south-west", "south", "south-east"];
    let a = d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU);
    NAMES[((a / (std::f32::consts::TAU / 8.0)).round() as usize) % 8]
}

fn alert_words(a: GuardAlert) -> &'static str {
    match a {
        GuardAlert::Patrolling => "patrolling",
        GuardAlert::Suspicious => "suspicious",
        GuardAlert::Investigating => "investigating a noise",
        GuardAlert::Chasing => "chasing Vive",
        GuardAlert::Returning => "going back to the round",
        GuardAlert::Searching => "searching the rooms around",
    }
}

/// The status line: time left, targets, alarm, and where each guard is relative to Vive.
pub fn status(session: &SessionView, guards: &[&GuardView], vive: Option<Vec2>) -> String {
    let mut out = match session.phase {
        Phase::Lobby => "The heist has not started.".to_owned(),
        Phase::Heist => capitalized(&format!("{} left.", duration_words(session.time_left_s))),
        Phase::Won => "The heist is won.".to_owned(),
        Phase::Lost(_) => "The heist is lost.".to_owned(),
    };
    let secured: Vec<&str> = session.targets.iter().filter(|t| t.1).map(|t| t.0.name()).collect();
    let missing: Vec<&str> = session.targets.iter().filter(|t| !t.1).map(|t| t.0.name()).collect();
    if !session.targets.is_empty() {
        out += &match (secured.is_empty(), missing.is_empty()) {
            (true, _) => format!(" Still to find: {}.", list(&missing)),
            (false, true) => " Every target is secured.".to_owned(),
            (false, false) => format!(" Secured: {}. Still to find: {}.", list(&secured), list(&missing)),
        };
    }
    out += &match session.alarm {
        0 => " No alarm yet.".to_owned(),
        n => format!(" Alarm level {}.", number_in_words(u32::from(n))),
    };
    if let Some(v) = vive {
        for g in guards {
            let d = g.position - v;
            out += &format!(
                " {}, {} metres {} of Vive, {}.",
                g.name,
                number_in_words(d.length().round() as u32),
                compass(d),
                alert_words(g.alert)
            );
        }
    }
    out
}

/// `text` with its first letter in capitals (a spoken sentence's start).
fn capitalized(text: &str) -> String {
    let mut chars = text.chars();
    chars.next().map(|c| c.to_uppercase().chain(chars).collect()).unwrap_or_default()
}

fn list(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => format!("the {one}"),
        [rest @ .., last] => format!("the {} and the {last}", rest.join(", the ")),
    }
}

/// What is said when an event arrives (None: the event is only heard, not spoken).
pub fn announce(event: &GameEvent, guard_name: impl Fn(u16) -> Option<String>) -> Option<String> {
    Some(match event {
        GameEvent::PhaseChanged(Phase::Heist) => "The heist has begun.".to_owned(),
        GameEvent::PhaseChanged(Phase::Won) => "All three pieces are secured. The heist is won!".to_owned(),
        GameEvent::PhaseChanged(Phase::Lost(reason)) => match reason {
            LossReason::Caught => "Vive was caught. The heist is lost.".to_owned(),
            LossReason::Time => "Time is up. The heist is lost.".to_owned(),
            LossReason::Alarm => "Too many wrong calls: the museum is locked down. The heist is lost.".to_owned(),
            LossReason::Abandoned => "A player left. The heist is over.".to_owned(),
        },
        GameEvent::GuardAlert { guard, alert: GuardAlert::Chasing, .. } => {
            format!("{} is chasing Vive!", guard_name(guard.0).unwrap_or_else(|| "A guard".into()))
        }
        GameEvent::GuardAlert { guard, alert: GuardAlert::Suspicious, .. } => {
            format!("{} heard something.", guard_name(guard.0).unwrap_or_else(|| "A guard".into()))
        }
        GameEvent::Alarm(level) => format!("Alarm level {}.", number_in_words(*level as u32)),
        GameEvent::Radio { guard, about, answering, .. } => {
            let caller = guard_name(guard.0).unwrap_or_else(|| "A guard".into());
            let what = match about {
                RadioAbout::Sighting => "he saw Vive",
                RadioAbout::Evidence => "he found a broken case",
            };
            let coming = match answering.len() {
                0 => "Nobody answers.".to_owned(),
                1 => format!("{} is coming.", guard_name(answering[0].0).unwrap_or_else(|| "a guard".into())),
                n => format!("{} guards are coming.", number_in_words(n as u32)),
            };
            format!("{caller} radios: {what}. {coming}")
        }
        GameEvent::Verdict { declared_real, outcome, .. } => match (outcome, declared_real) {
            (VerdictOutcome::Secured, _) => "Correct. It was the real one: secured.".to_owned(),
            (VerdictOutcome::Discarded, _) => "Correct. It was a fake: thrown away.".to_owned(),
            (VerdictOutcome::Wrong, true) => "Wrong: that one is a fake. The alarm goes up.".to_owned(),
            (VerdictOutcome::Wrong, false) => "Wrong: that one was real. The alarm goes up.".to_owned(),
        },
        GameEvent::Warning(w) => format!("You told Vive to {}.", warning_words(*w)),
        GameEvent::WarningSeen(w) => format!("Vive has your warning to {}.", warning_words(*w)),
        _ => return None,
    })
}

/// What a warning tells Vive to do.
fn warning_words(w: WarningKind) -> &'static str {
    match w {
        WarningKind::Hide => "hide",
        WarningKind::Go => "go",
        WarningKind::ComeBack => "come back",
    }
}

/// "A copy of the crown is on the bench."
pub fn copy_arrived(kind: Option<ArtifactKind>) -> String {
    match kind {
        Some(k) => format!("A copy of the {} is on the bench.", k.name()),
        None => "A copy is on the bench.".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::protocol::GuardId;

    #[test]
    fn durations_read_naturally() {
        assert_eq!(duration_words(125.0), "two minutes and five seconds");
        assert_eq!(duration_words(60.0), "one minute");
        assert_eq!(duration_words(1.2), "one second");
    }

    #[test]
    fn the_compass_points_the_right_way() {
        assert_eq!(compass(Vec2::new(0.0, 5.0)), "north");
        assert_eq!(compass(Vec2::new(3.0, 3.0)), "north-east");
        assert_eq!(compass(Vec2::new(-4.0, 0.1)), "west");
        assert_eq!(compass(Vec2::new(0.5, -6.0)), "south");
    }

    #[test]
    fn the_status_names_time_targets_alarm_and_guards_relative_to_vive() {
        let session = SessionView {
            phase: Phase::Heist,
            time_left_s: 301.0,
            alarm: 1,
            targets: vec![(ArtifactKind::Crown, true), (ArtifactKind::Amphora, false), (ArtifactKind::Idol, false)],
            present: (true, true),
            difficulty: Default::default(),
        };
        let clara = GuardView {
            id: GuardId(0),
            name: "Clara".into(),
            position: Vec2::new(5.0, 8.0),
            facing: 0.0,
            alert: GuardAlert::Patrolling,
        };
        let s = status(&session, &[&clara], Some(Vec2::new(5.0, 2.0)));
        assert_eq!(
            s,
            "Five minutes and one second left. Secured: the crown. Still to find: the amphora and the idol. \
Alarm level one. Clara, six metres north of Vive, patrolling."
        );
        assert!(!s.chars().any(|c| c.is_ascii_digit()));
        let calm = SessionView { alarm: 0, ..session };
        assert!(status(&calm, &[], None).contains(" No alarm yet."), "no 'alarm level no'");
    }

    #[test]
    fn verdicts_and_the_end_are_announced() {
        let e = GameEvent::Verdict {
            item: heist_shared::protocol::ItemId(3),
            declared_real: true,
            outcome: VerdictOutcome::Wrong,
        };
        assert!(announce(&e, |_| None).expect("spoken").starts_with("Wrong"));
        let won = announce(&GameEvent::PhaseChanged(Phase::Won), |_| None).expect("spoken");
        assert!(won.contains("won"));
    }
}
