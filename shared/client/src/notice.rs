//! What each player is told about the session itself — the partner coming and going, rounds, the end —
//! in words both clients use (spoken by Phantom's, shown on Vive's HUD).

use heist_shared::protocol::{DisconnectReason, GameEvent, Role};

/// The line for a session event as heard by `me`; `None` for game events (each client words those) and
/// for news of oneself that needs no telling.
pub fn session_notice(event: &GameEvent, me: Role) -> Option<String> {
    let partner = |r: Role| r != me;
    Some(match *event {
        GameEvent::Joined(r) if partner(r) => format!("{r} joined."),
        GameEvent::Left { role, dropped: false } if partner(role) => format!("{role} left the session."),
        GameEvent::Left { role, dropped: true } if partner(role) => {
            format!("{role}'s connection dropped.")
        }
        GameEvent::RematchAsked(r) if partner(r) => format!("{r} asks for another round."),
        GameEvent::RematchAsked(_) => "You asked for another round.".to_owned(),
        GameEvent::RoundStarted(n) => format!("Round {n} begins, with new copies."),
        GameEvent::EndingSoon(s) => format!("The session ends in {s} seconds unless you both ask for another round."),
        _ => return None,
    })
}

/// A change of the connection, as a line for the player (`was`: the state before).
pub fn link_notice(was: crate::Link, now: crate::Link) -> Option<&'static str> {
    use crate::Link;
    match (was, now) {
        (Link::Up, Link::Silent) => Some("The connection to the server is lost. Waiting for it to come back."),
        (Link::Silent, Link::Up) => Some("The connection is back."),
        (Link::Connecting, Link::Silent) => Some("The server does not answer."),
        (_, Link::Gone) => Some("The server is gone: the session is over for us."),
        _ => None,
    }
}

/// The line for the link's change from `was` to `now`, unless it ended for a reason the player already
/// has: the server said why ([`disconnect_notice`]) or the player is leaving.
pub fn link_change_notice(
    was: crate::Link,
    now: crate::Link,
    inbox: &crate::Inbox,
    leaving: &crate::Leaving,
) -> Option<&'static str> {
    let explained = inbox.disconnect.is_some() || leaving.since.is_some();
    if now == crate::Link::Gone && explained { None } else { link_notice(was, now) }
}

/// Why the server let us go, as a line for the player.
pub fn disconnect_notice(reason: &DisconnectReason) -> String {
    match reason {
        DisconnectReason::RoleTaken(r) => format!("The server refused us: someone already plays {r}."),
        DisconnectReason::BadToken => "The server refused our token: join again with a fresh code.".to_owned(),
        DisconnectReason::Abuse => "The server disconnected us for sending too many refused messages.".to_owned(),
        DisconnectReason::SessionEnded => "The session is over. Thank you for playing.".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_partner_is_named_and_oneself_is_not_announced() {
        assert_eq!(session_notice(&GameEvent::Joined(Role::Vive), Role::Phantom).as_deref(), Some("Vive joined."));
        assert_eq!(session_notice(&GameEvent::Joined(Role::Phantom), Role::Phantom), None);
        let dropped = GameEvent::Left { role: Role::Phantom, dropped: true };
        assert_eq!(session_notice(&dropped, Role::Vive).as_deref(), Some("Phantom's connection dropped."));
        let left = GameEvent::Left { role: Role::Phantom, dropped: false };
        assert_eq!(session_notice(&left, Role::Vive).as_deref(), Some("Phantom left the session."));
    }

    #[test]
    fn losing_and_finding_the_server_is_said_once_each() {
        use crate::Link;
        assert!(link_notice(Link::Up, Link::Silent).is_some_and(|l| l.contains("lost")));
        assert_eq!(link_notice(Link::Silent, Link::Up), Some("The connection is back."));
        assert!(link_notice(Link::Silent, Link::Gone).is_some_and(|l| l.contains("gone")));
        assert_eq!(link_notice(Link::Connecting, Link::Up), None, "connecting is no news");
    }

    #[test]
    fn a_lost_server_is_not_announced_when_the_end_was_already_explained() {
        use crate::{Inbox, Leaving, Link};
        let (mut inbox, mut leaving) = (Inbox::default(), Leaving::default());
        assert!(link_change_notice(Link::Up, Link::Gone, &inbox, &leaving).is_some_and(|l| l.contains("gone")));
        leaving.start(1.0);
        assert_eq!(link_change_notice(Link::Up, Link::Gone, &inbox, &leaving), None, "we left");
        let leaving = Leaving::default();
        inbox.disconnect = Some(DisconnectReason::SessionEnded);
        assert_eq!(link_change_notice(Link::Up, Link::Gone, &inbox, &leaving), None, "the server said why");
        assert!(link_change_notice(Link::Up, Link::Silent, &inbox, &leaving).is_some(), "only the end is muted");
    }

    #[test]
    fn a_rematch_request_reads_differently_for_who_asked() {
        let asked = GameEvent::RematchAsked(Role::Vive);
        assert_eq!(session_notice(&asked, Role::Phantom).as_deref(), Some("Vive asks for another round."));
        assert_eq!(session_notice(&asked, Role::Vive).as_deref(), Some("You asked for another round."));
        assert!(session_notice(&GameEvent::RoundStarted(2), Role::Vive).is_some_and(|l| l.starts_with("Round 2")));
        assert_eq!(session_notice(&GameEvent::Alarm(1), Role::Vive), None);
    }
}
