//! The server's walkie-talkie relay, attacked and checked over loopback UDP: a voice frame reaches the
//! sender's partner and nobody else (not the sender, not a client of another session); a flood of voice
//! frames is cut to the voice rate and its sender disconnected while the partner plays on; forged
//! frames count against their sender. Plain client cores write the frames, as any client could.

use bevy::prelude::*;
use heist_server::build_server;
use heist_shared::protocol::voice::{ClientVoice, MAX_VOICE_BYTES, PartnerVoice, VoiceFrame};
use heist_shared::protocol::{DisconnectReason, Role};
use heist_tests::{HZ, Session};

/// Voice frames a client received.
#[derive(Resource, Default)]
struct Heard(Vec<VoiceFrame>);

fn hear(mut frames: MessageReader<PartnerVoice>, mut heard: ResMut<Heard>) {
    heard.0.extend(frames.read().map(|f| f.0.clone()));
}

fn listening(app: &mut App) {
    app.init_resource::<Heard>().add_systems(PreUpdate, hear);
}

fn heard(app: &App) -> &[VoiceFrame] {
    &app.world().resource::<Heard>().0
}

fn frame(seq: u16) -> ClientVoice {
    ClientVoice::Frame(VoiceFrame { seq, end: false, opus: vec![0xf8, seq as u8, 7] })
}

#[test]
fn a_voice_frame_reaches_the_partner_in_the_same_session_and_no_one_else() {
    const SESSIONS: usize = 3;
    let mut server = build_server(heist_server::load::load_server_options(SESSIONS)).expect("server starts");
    let endpoint = server.tokens.as_ref().expect("tokens").addr;
    let timeout = std::time::Duration::from_secs(5);
    // Three sessions of two plain clients each: [vive, phantom] per session.
    let mut clients: Vec<App> = Vec::new();
    for _ in 0..SESSIONS {
        let (code, token) = heist_client::create_session(endpoint, Role::Vive, timeout).expect("a session");
        clients.push(heist_server::demo::client_with_token(token, listening).expect("Vive joins"));
        let token = heist_client::request_token(endpoint, &code, Role::Phantom, timeout).expect("a token");
        clients.push(heist_server::demo::client_with_token(token, listening).expect("Phantom joins"));
    }
    let step = |server: &mut heist_server::HostedServer, clients: &mut Vec<App>| {
        server.update();
        clients.iter_mut().for_each(App::update);
    };
    for _ in 0..2 * HZ {
        step(&mut server, &mut clients);
    }
    assert!(server.sessions().iter().all(|s| s.game.present == (true, true)), "every seat is taken");
    // Session 0's Vive talks for a second; session 1's Phantom says one frame.
    for t in 0..HZ as u16 {
        if t % 3 != 2 {
            clients[0].world_mut().write_message(frame(t));
        }
        if t == 10 {
            clients[3].world_mut().write_message(frame(500));
        }
        step(&mut server, &mut clients);
    }
    for _ in 0..10 {
        step(&mut server, &mut clients);
    }
    let got: Vec<usize> = clients.iter().map(|c| heard(c).len()).collect();
    assert_eq!(got, vec![0, 40, 1, 0, 0, 0], "frames heard by each client");
    assert!(heard(&clients[1]).iter().enumerate().all(|(i, f)| f.seq == (i as u16 / 2) * 3 + i as u16 % 2));
    assert_eq!(heard(&clients[2])[0].seq, 500, "session 1's Vive heard its own partner");
}

#[test]
fn a_voice_flood_is_cut_to_the_voice_rate_and_its_sender_disconnected_while_the_partner_plays_on() {
    let mut s = Session::new(3);
    let vive = s.join(Role::Vive, listening);
    let phantom = s.join(Role::Phantom, listening);
    assert!(s.step_until(5 * HZ, |s| s.server.game().present == (true, true)));
    // 200 frames a tick (12,000 a second) from Phantom, for up to 5 s.
    let mut seq = 0u16;
    for _ in 0..5 * HZ {
        for _ in 0..200 {
            s.clients[phantom].world_mut().write_message(frame(seq));
            seq = seq.wrapping_add(1);
        }
        s.step();
        if s.inbox(phantom).disconnect.is_some() {
            break;
        }
    }
    s.step_until(HZ, |_| false);
    assert_eq!(s.inbox(phantom).disconnect, Some(DisconnectReason::Abuse), "the flooder is let go");
    let passed = heard(&s.clients[vive]).len();
    assert!(passed <= 30 + 5 * 60, "Vive got at most the voice rate's worth: {passed}");
    assert!(s.inbox(vive).disconnect.is_none(), "Vive plays on");
    assert!(s.server.game().is_present(Role::Vive));
    let metrics = s.server.fleet.metrics.encode();
    let refused =
        heist_server::fleet::metrics::sample(&metrics, r#"heist_refused_total{stage="voice",reason="rate_limited"}"#);
    assert!(refused.is_some_and(|n| n > 100.0), "the cut frames are counted: {refused:?}");
}

#[test]
fn forged_or_oversized_voice_frames_are_dropped_and_held_against_the_sender() {
    let mut s = Session::new(4);
    let vive = s.join(Role::Vive, listening);
    let phantom = s.join(Role::Phantom, listening);
    assert!(s.step_until(5 * HZ, |s| s.server.game().present == (true, true)));
    // The client core sends whatever frame it is given: the server's decoder is the check.
    for i in 0..3 * HZ {
        let big = ClientVoice::Frame(VoiceFrame { seq: i as u16, end: false, opus: vec![1; MAX_VOICE_BYTES + 1] });
        s.clients[vive].world_mut().write_message(big);
        s.clients[vive].world_mut().write_message(ClientVoice::Malformed);
        s.step();
        if s.inbox(vive).disconnect.is_some() {
            break;
        }
    }
    s.step_until(HZ, |_| false);
    assert!(heard(&s.clients[phantom]).is_empty(), "nothing forged was relayed");
    assert_eq!(s.inbox(vive).disconnect, Some(DisconnectReason::Abuse), "two refusals a tick add up");
    assert!(s.inbox(phantom).disconnect.is_none());
}
