//! Client messages into the game: decode (already done by the protocol), check the rate, apply or refuse.

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use heist_shared::protocol::{ClientMsg, DisconnectReason, LobbyMsg, ServerMsg};

use super::admission::{Player, refuse_and_disconnect};
use super::settings::NetSettings;
use crate::session::Session;

/// A gap between two frames longer than this in wall-clock time (whatever the app's clock says: a stepped
/// one does not see it), seconds, means the server stood still (a long tick, a paused process): the
/// messages its clients kept sending meanwhile arrive in the next frames, and what the rates refuse of
/// that backlog for [`STALL_GRACE_S`] is refused but not held against them (it expelled every player
/// after a few seconds' stall).
const STALL_S: f64 = 0.5;
/// Seconds (wall clock) after a stall during which refusals are not counted as abuse.
const STALL_GRACE_S: f64 = 2.0;

/// When the last frame ran, and until when refusals are forgiven (wall clock).
#[derive(Default)]
pub struct StallWatch {
    last: Option<std::time::Instant>,
    grace_until: Option<std::time::Instant>,
}

impl StallWatch {
    /// Notes a frame at `now`; true while refusals are forgiven.
    fn forgiving(&mut self, now: std::time::Instant) -> bool {
        if self.last.is_some_and(|last| now.duration_since(last).as_secs_f64() > STALL_S) {
            self.grace_until = Some(now + std::time::Duration::from_secs_f64(STALL_GRACE_S));
        }
        self.last = Some(now);
        self.grace_until.is_some_and(|until| now < until)
    }
}

/// Applies every message received this frame, in order.
#[allow(clippy::too_many_arguments)]
pub fn apply_client_messages(
    mut received: MessageReader<FromClient<ClientMsg>>,
    mut players: Query<&mut Player>,
    mut sessions: Query<&mut Session>,
    settings: Res<NetSettings>,
    time: Res<Time<Real>>,
    mut messages: MessageWriter<ToClients<ServerMsg>>,
    mut disconnects: MessageWriter<DisconnectRequest>,
    mut stalls: Local<StallWatch>,
) {
    let leak = time.delta_secs();
    let after_a_stall = stalls.forgiving(std::time::Instant::now());
    for mut player in &mut players {
        player.strikes = (player.strikes - leak).max(0.0);
    }
    for FromClient { client_id, message } in received.read() {
        let ClientId::Client(client) = *client_id else { continue };
        let Ok(mut player) = players.get_mut(client) else {
            // Not admitted (yet, or refused): nothing it says counts.
            continue;
        };
        if player.expelled {
            continue; // being disconnected: nothing more it says counts
        }
        let Ok(mut session) = sessions.get_mut(player.session) else { continue };
        let Session { game, log, .. } = &mut *session;
        let now = time.elapsed_secs_f64();
        let applied = player.limits.check(message, now).and_then(|()| game.apply(player.role, message));
        if applied.is_ok() && *message == ClientMsg::Lobby(LobbyMsg::Leave) {
            player.leaving = true;
            disconnects.write(DisconnectRequest { client });
        }
        if let Err(refusal) = applied {
            settings.metrics.refuse("message", refusal.kind());
            if !after_a_stall {
                player.strikes += 1.0;
            }
            let peer = player.peer.map_or_else(|| "?".to_owned(), |p| p.to_string());
            info!("refused a {} message from {peer}: {refusal:?}", player.role);
            log.debug(game.elapsed_s, format!("{} refused: {refusal:?}", player.role));
            messages.write(ToClients {
                targets: SendTargets::Single(ClientId::Client(client)),
                message: ServerMsg::Refused(refusal),
            });
            if player.strikes > settings.abuse_limit as f32 {
                player.expelled = true;
                warn!("disconnecting {} at {peer} for abuse", player.role);
                log.line(game.elapsed_s, format!("{} disconnected for abuse", player.role));
                refuse_and_disconnect(client, DisconnectReason::Abuse, &mut messages, &mut disconnects);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    #[test]
    fn refusals_are_forgiven_for_a_while_after_the_server_stood_still_and_only_then() {
        let mut watch = StallWatch::default();
        let t0 = Instant::now();
        assert!(!watch.forgiving(t0));
        assert!(!watch.forgiving(t0 + Duration::from_millis(16)), "a normal frame");
        let after = t0 + Duration::from_secs(5);
        assert!(watch.forgiving(after), "the frame after a 5 s stall");
        // Frames every 100 ms after it: forgiven for 2 s, then not.
        let forgiven: Vec<bool> = (1..=30).map(|i| watch.forgiving(after + Duration::from_millis(100 * i))).collect();
        assert!(forgiven[..19].iter().all(|f| *f), "within the grace: {forgiven:?}");
        assert!(forgiven[20..].iter().all(|f| !*f), "the grace is over: {forgiven:?}");
    }
}
