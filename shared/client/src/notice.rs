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
            format!("{role}'s connection dropped. Their seat is kept for a minute; a heist stands still meanwhile.")
        }
        GameEvent::Resumed(r) if partner(r) => format!("{r} is back."),
        GameEvent::Resumed(_) => "You are back in your seat.".to_owned(),
        GameEvent::GaveUp(r) if partner(r) => format!("{r} did not come back in time."),
        GameEvent::RematchAsked(r) if partner(r) => format!("{r} asks for another round."),
        GameEvent::RematchAsked(_) => "You asked for another round.".to_owned(),
        GameEvent::RoundStarted(n) => format!("Round {n} begins, with new copies."),
        GameEvent::EndingSoon(s) => format!("The session ends in {s} seconds unless you both ask for another round."),
        GameEvent::ServerClosing { within_s } => format!(
            "The server is shutting down. A heist under way may finish, within {} at most; no new round after it.",
            spoken_duration(within_s)
        ),
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
        (_, Link::Gone) => {
            Some("The server is gone. If it comes back within a minute, join again to take your seat back.")
        }
        _ => None,
    }
}

/// The line for the link's change from `was` to `now`, unless it ended for a reason the player already
/// has: the server said why ([`disconnect_notice`]), the player is leaving, or the client is trying to
/// get back in ([`reconnect_notice`] tells that).
pub fn link_change_notice(
    was: crate::Link,
    now: crate::Link,
    inbox: &crate::Inbox,
    leaving: &crate::Leaving,
    reconnect: &crate::Reconnect,
) -> Option<&'static str> {
    let explained = inbox.disconnect.is_some() || leaving.since.is_some() || reconnect.is_trying();
    if now == crate::Link::Gone && explained { None } else { link_notice(was, now) }
}

/// A change of [`crate::Reconnect`] as a line for the player: that the client tries to get back in
/// (once), and why it gave up. Being back is told by the server's `Resumed` ([`session_notice`]).
pub fn reconnect_notice(was: &crate::Reconnect, now: &crate::Reconnect) -> Option<String> {
    use crate::Reconnect;
    match (was, now) {
        (Reconnect::Steady, Reconnect::Trying { .. }) => Some("Trying to get back into the session.".to_owned()),
        (_, Reconnect::GaveUp(why)) if !matches!(was, Reconnect::GaveUp(_)) => {
            Some(format!("Could not get back into the session: {why}."))
        }
        _ => None,
    }
}

/// What a client tells its player about the connection, each once: why the server let us go, the link's
/// changes, trying to get back in and giving up. Keep one per app and ask for [`LinkNews::news`] each frame.
#[derive(Debug, Default)]
pub struct LinkNews {
    link: crate::Link,
    reconnect: crate::Reconnect,
    told_disconnect: bool,
}

impl LinkNews {
    /// The lines to tell now, in order (none when nothing changed).
    pub fn news(
        &mut self,
        link: crate::Link,
        inbox: &crate::Inbox,
        leaving: &crate::Leaving,
        reconnect: &crate::Reconnect,
    ) -> Vec<String> {
        let mut lines = Vec::new();
        if let Some(reason) = &inbox.disconnect
            && !self.told_disconnect
        {
            self.told_disconnect = true;
            lines.push(disconnect_notice(reason));
        }
        if link != self.link {
            lines.extend(link_change_notice(self.link, link, inbox, leaving, reconnect).map(str::to_owned));
            self.link = link;
        }
        if *reconnect != self.reconnect {
            lines.extend(reconnect_notice(&self.reconnect, reconnect));
            self.reconnect = reconnect.clone();
        }
        lines
    }
}

/// Why the server let us go, as a line for the player.
pub fn disconnect_notice(reason: &DisconnectReason) -> String {
    match reason {
        DisconnectReason::RoleTaken(r) => format!("The server refused us: someone already plays {r}."),
        DisconnectReason::BadToken => "The server refused our token: join again with a fresh code.".to_owned(),
        DisconnectReason::Abuse => "The server disconnected us for sending too many refused messages.".to_owned(),
        DisconnectReason::SessionEnded => "The session is over. Thank you for playing.".to_owned(),
        DisconnectReason::SeatHeld(r) => {
            format!("The server refused us: the {r} seat is kept for the player who dropped from it.")
        }
        DisconnectReason::BadSeat => "The server refused our seat ticket: join again with the code.".to_owned(),
        DisconnectReason::Replaced => "This seat was taken back by our own new connection.".to_owned(),
        DisconnectReason::ServerShutdown => "The server has shut down. Thank you for playing.".to_owned(),
    }
}

/// Seconds as a player hears them: "90 seconds", "10 minutes", "1 minute 30 seconds".
fn spoken_duration(s: u32) -> String {
    let unit = |n: u32, one: &str| if n == 1 { format!("1 {one}") } else { format!("{n} {one}s") };
    match (s / 60, s % 60) {
        (0, secs) => unit(secs, "second"),
        (mins, 0) => unit(mins, "minute"),
        (mins, secs) => format!("{} {}", unit(mins, "minute"), unit(secs, "second")),
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
        let heard = session_notice(&dropped, Role::Vive).unwrap();
        assert!(heard.starts_with("Phantom's connection dropped.") && heard.contains("seat is kept"), "{heard}");
        assert_eq!(session_notice(&GameEvent::Resumed(Role::Phantom), Role::Vive).as_deref(), Some("Phantom is back."));
        assert!(session_notice(&GameEvent::GaveUp(Role::Vive), Role::Phantom).is_some_and(|l| l.contains("did not")));
        let left = GameEvent::Left { role: Role::Phantom, dropped: false };
        assert_eq!(session_notice(&left, Role::Vive).as_deref(), Some("Phantom left the session."));
    }

    #[test]
    fn losing_and_finding_the_server_is_said_once_each() {
        use crate::Link;
        assert!(link_notice(Link::Up, Link::Silent).is_some_and(|l| l.contains("lost")));
        assert_eq!(link_notice(Link::Silent, Link::Up), Some("The connection is back."));
        assert!(link_notice(Link::Silent, Link::Gone).is_some_and(|l| l.contains("gone") && l.contains("seat back")));
        assert_eq!(link_notice(Link::Connecting, Link::Up), None, "connecting is no news");
    }

    #[test]
    fn a_lost_server_is_not_announced_when_the_end_was_already_explained() {
        use crate::{Inbox, Leaving, Link, Reconnect};
        let (mut inbox, mut leaving, steady) = (Inbox::default(), Leaving::default(), Reconnect::Steady);
        let gone = link_change_notice(Link::Up, Link::Gone, &inbox, &leaving, &steady);
        assert!(gone.is_some_and(|l| l.contains("gone")));
        let trying = Reconnect::Trying { attempts: 1 };
        assert_eq!(link_change_notice(Link::Silent, Link::Gone, &inbox, &leaving, &trying), None, "coming back");
        leaving.start(1.0);
        assert_eq!(link_change_notice(Link::Up, Link::Gone, &inbox, &leaving, &steady), None, "we left");
        let leaving = Leaving::default();
        inbox.disconnect = Some(DisconnectReason::SessionEnded);
        assert_eq!(link_change_notice(Link::Up, Link::Gone, &inbox, &leaving, &steady), None, "the server said why");
        let silent = link_change_notice(Link::Up, Link::Silent, &inbox, &leaving, &steady);
        assert!(silent.is_some(), "only the end is muted");
    }

    #[test]
    fn trying_to_come_back_is_said_once_and_giving_up_says_why() {
        use crate::Reconnect;
        let (steady, trying) = (Reconnect::Steady, Reconnect::Trying { attempts: 1 });
        assert!(reconnect_notice(&steady, &trying).is_some_and(|l| l.starts_with("Trying to get back")));
        assert_eq!(reconnect_notice(&trying, &Reconnect::Trying { attempts: 2 }), None, "once, not per attempt");
        assert_eq!(reconnect_notice(&trying, &steady), None, "the server's Resumed tells it");
        let gave_up = Reconnect::GaveUp("no way back into the session for 60 s".into());
        let line = reconnect_notice(&trying, &gave_up).unwrap();
        assert_eq!(line, "Could not get back into the session: no way back into the session for 60 s.");
    }

    #[test]
    fn link_news_tells_each_change_once_and_the_reason_before_the_rest() {
        use crate::{Inbox, Leaving, Link, Reconnect};
        let (mut news, mut inbox, leaving) = (LinkNews::default(), Inbox::default(), Leaving::default());
        let trying = Reconnect::Trying { attempts: 1 };
        let steady = Reconnect::Steady;
        assert!(news.news(Link::Up, &inbox, &leaving, &steady).is_empty(), "connecting to up is no news");
        let lost = news.news(Link::Silent, &inbox, &leaving, &trying);
        assert_eq!(lost.len(), 2, "{lost:?}");
        assert!(lost[0].contains("lost") && lost[1].starts_with("Trying to get back"), "{lost:?}");
        assert!(news.news(Link::Silent, &inbox, &leaving, &trying).is_empty(), "said once");
        inbox.disconnect = Some(DisconnectReason::SessionEnded);
        let ended = news.news(Link::Gone, &inbox, &leaving, &steady);
        assert_eq!(ended, vec![disconnect_notice(&DisconnectReason::SessionEnded)], "the reason, not 'gone'");
        assert!(news.news(Link::Gone, &inbox, &leaving, &steady).is_empty());
    }

    #[test]
    fn a_rematch_request_reads_differently_for_who_asked() {
        let asked = GameEvent::RematchAsked(Role::Vive);
        assert_eq!(session_notice(&asked, Role::Phantom).as_deref(), Some("Vive asks for another round."));
        assert_eq!(session_notice(&asked, Role::Vive).as_deref(), Some("You asked for another round."));
        assert!(session_notice(&GameEvent::RoundStarted(2), Role::Vive).is_some_and(|l| l.starts_with("Round 2")));
        let closing = session_notice(&GameEvent::ServerClosing { within_s: 630 }, Role::Phantom).unwrap();
        assert!(closing.contains("shutting down") && closing.contains("10 minutes 30 seconds"), "{closing}");
        assert_eq!(spoken_duration(1), "1 second");
        assert_eq!(spoken_duration(60), "1 minute");
        assert_eq!(session_notice(&GameEvent::Alarm(1), Role::Vive), None);
    }
}
