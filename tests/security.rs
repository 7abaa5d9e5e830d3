//! The server refuses what it must, and nothing a client sends harms the session or leaks the truth.

use bevy::prelude::*;
use bevy_replicon::shared::message::registry::RemoteMessageRegistry;
use bevy_replicon_renet::RenetClient;
use glam::{Quat, Vec2, Vec3};
use heist_client::JoinError;
use heist_server::ServerOptions;
use heist_shared::protocol::join::JoinRefusal;
use heist_shared::protocol::{
    CaseId, ClientMsg, DisconnectReason, GameEvent, ItemId, ItemKind, ItemView, LobbyMsg, PhantomMsg, PhantomTool,
    Phase, Refusal, Role, ViveMsg, WarningKind,
};
use heist_tests::{HZ, Session, join};

/// Both players joined and ready; returns (session, vive index, phantom index).
fn heist_in_progress() -> (Session, usize, usize) {
    let mut s = Session::new(11);
    let vive = s.join(Role::Vive, |_| {});
    let phantom = s.join(Role::Phantom, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.inbox(vive).role.is_some() && s.inbox(phantom).role.is_some()));
    s.send(vive, ClientMsg::Lobby(LobbyMsg::Ready));
    s.send(phantom, ClientMsg::Lobby(LobbyMsg::Ready));
    assert!(s.step_until(5 * HZ, |s| s.server.game().phase == Phase::Heist), "the heist starts");
    (s, vive, phantom)
}

fn send_raw(s: &mut Session, client: usize, bytes: &[u8]) {
    let world = s.clients[client].world_mut();
    let channel = world
        .resource::<RemoteMessageRegistry>()
        .client_message_channel::<ClientMsg>()
        .expect("ClientMsg is registered");
    world.resource_mut::<RenetClient>().send_message(channel as u8, bytes.to_vec());
}

#[test]
fn a_second_claimant_of_a_role_is_refused_at_the_token_endpoint() {
    let mut s = Session::new(1);
    let _vive = s.join(Role::Vive, |_| {});
    assert!(s.step_until(5 * HZ, |s| s.server.game().is_present(Role::Vive)));
    match join(&s.server, Role::Vive, |_| {}) {
        Err(e) => match e.downcast::<JoinError>() {
            Ok(JoinError::Refused(reason)) => assert_eq!(reason, JoinRefusal::RoleTaken(Role::Vive)),
            other => panic!("unexpected error {other:?}"),
        },
        Ok(_) => panic!("a second Vive got a token"),
    }
}

#[test]
fn a_role_thief_holding_a_token_is_disconnected_with_the_reason() {
    let mut s = Session::new(2);
    // Both tokens are minted before either player connects, so only the server can stop the thief.
    let first = join(&s.server, Role::Vive, |_| {}).unwrap();
    let thief = join(&s.server, Role::Vive, |_| {}).unwrap();
    s.clients.push(first);
    assert!(s.step_until(5 * HZ, |s| s.inbox(0).role == Some(Role::Vive)));
    s.clients.push(thief);
    assert!(s.step_until(5 * HZ, |s| s.inbox(1).disconnect.is_some()), "the thief is told");
    assert_eq!(s.inbox(1).disconnect, Some(DisconnectReason::RoleTaken(Role::Vive)));
    assert_eq!(s.inbox(1).role, None, "the thief was never welcomed");
    s.step_until(HZ, |_| false);
    assert!(s.clients[1].world().resource::<RenetClient>().is_disconnected());
    assert!(s.server.game().is_present(Role::Vive), "the real Vive is still in");
}

#[test]
fn malformed_and_illegal_messages_are_refused_without_harming_the_session() {
    let (mut s, vive, phantom) = heist_in_progress();
    send_raw(&mut s, vive, &[0xFF, 0xFF, 0xFF, 0x13, 0x37]);
    s.send(vive, ClientMsg::Phantom(PhantomMsg::Verdict { item: ItemId(0), real: true }));
    s.send(
        vive,
        ClientMsg::Vive(ViveMsg::Move {
            seq: 1,
            direction: Vec2::new(40.0, 0.0),
            gait: Default::default(),
            facing: 0.0,
        }),
    );
    s.send(vive, ClientMsg::Vive(ViveMsg::Break(CaseId(0))));
    s.send(vive, ClientMsg::Vive(ViveMsg::Break(CaseId(999))));
    s.send(phantom, ClientMsg::Phantom(PhantomMsg::Verdict { item: ItemId(0), real: false }));
    let before = s.server.game().vive.position;
    assert!(s.step_until(5 * HZ, |s| s.inbox(vive).refusals.len() >= 5 && !s.inbox(phantom).refusals.is_empty()));
    let refusals = &s.inbox(vive).refusals;
    assert!(matches!(&refusals[0], Refusal::Malformed(reason) if reason.contains("undecodable")), "{refusals:?}");
    assert_eq!(refusals[1..5], [Refusal::WrongRole, Refusal::TooFast, Refusal::OutOfReach, Refusal::Unknown]);
    assert_eq!(s.inbox(phantom).refusals, [Refusal::NotOnWorkbench], "Phantom only hears about its own mistake");
    assert_eq!(s.server.game().phase, Phase::Heist);
    assert_eq!(s.server.game().vive.position, before, "the too-fast move was not applied");
    assert!(s.server.game().cases.iter().all(|c| !c.broken));
    assert_eq!(s.client_phase(phantom), Some(Phase::Heist));
}

#[test]
fn sustained_abuse_disconnects_only_the_abuser() {
    let (mut s, vive, phantom) = heist_in_progress();
    for i in 0..120u8 {
        send_raw(&mut s, vive, &[0xF0, i, 0xAA]);
    }
    assert!(s.step_until(10 * HZ, |s| s.inbox(vive).disconnect.is_some()));
    assert_eq!(s.inbox(vive).disconnect, Some(DisconnectReason::Abuse));
    assert!(s.step_until(5 * HZ, |s| !s.server.game().is_present(Role::Vive)));
    assert!(s.server.game().is_present(Role::Phantom));
    assert!(s.inbox(phantom).refusals.is_empty());
    assert!(s.clients[phantom].world().resource::<RenetClient>().is_connected());
}

#[test]
fn no_client_ever_receives_which_copy_is_real() {
    // Bots play a while so copies move, cases break and copies reach the workbench.
    let mut heist =
        heist_server::demo::Heist::start(ServerOptions::local_test(6), heist_bots::ViveStyle::Careful).unwrap();
    for _ in 0..(240 * HZ) {
        heist.step();
        if !heist.server.game().is_running() {
            break;
        }
    }
    let phantom_inbox = heist.phantom.world().resource::<heist_client::Inbox>();
    assert!(phantom_inbox.received.workbench >= 1, "a copy reached the workbench");
    let vive_inbox = heist.vive.world().resource::<heist_client::Inbox>();
    assert_eq!(vive_inbox.received.workbench, 0, "the VR side never gets haptic geometry");
    assert_eq!(vive_inbox.received.briefings, 0);

    for app in [&mut heist.vive, &mut heist.phantom] {
        let world = app.world_mut();
        let items: Vec<ItemView> = world.query::<&ItemView>().iter(world).cloned().collect();
        assert!(items.len() >= 9);
        // All copies of one artifact look the same; nothing replicated mentions realness.
        for a in &items {
            for b in &items {
                if let (ItemKind::Copy { artifact: x, look: lx }, ItemKind::Copy { artifact: y, look: ly }) =
                    (&a.kind, &b.kind)
                    && x == y
                {
                    assert_eq!(lx, ly);
                }
            }
            let text = ron::to_string(a).unwrap().to_lowercase();
            assert!(!text.contains("real") && !text.contains("fake") && !text.contains("truth"), "{text}");
        }
    }
    // The truth exists only on the server.
    assert!(heist.server.game().items.iter().filter_map(|i| i.truth.as_ref()).any(|t| t.real));
}

#[test]
fn bots_never_send_anything_the_server_refuses() {
    for style in [heist_bots::ViveStyle::Reckless, heist_bots::ViveStyle::Careful] {
        let mut heist = heist_server::demo::Heist::start(ServerOptions::local_test(8), style).unwrap();
        heist.run(90.0);
        for app in [&heist.vive, &heist.phantom] {
            let inbox = app.world().resource::<heist_client::Inbox>();
            assert!(inbox.role.is_some(), "the bot was welcomed");
            assert!(inbox.refusals.is_empty(), "{style:?}: {:?}", inbox.refusals);
        }
    }
}

#[test]
fn an_insecure_server_admits_a_tokenless_client_by_its_claimed_role() {
    let mut options = ServerOptions::local_test(4);
    options.insecure = true;
    let mut s = Session::with_options(options);
    assert!(s.server.tokens.is_none(), "no token endpoint in insecure mode");
    let mut app = heist_server::demo::stepped_client_app();
    app.finish();
    app.cleanup();
    heist_client::connect_insecure(&mut app, s.server.addr, Role::Phantom).unwrap();
    s.clients.push(app);
    assert!(s.step_until(5 * HZ, |s| s.inbox(0).role == Some(Role::Phantom)));
    assert!(s.server.game().is_present(Role::Phantom));
}

#[test]
fn the_speed_hack_is_refused_and_gains_no_ground() {
    let (mut s, vive, _phantom) = heist_in_progress();
    let start = s.server.game().vive.position;
    // Every frame: a second's worth of moves east, then an action to fast-forward them.
    let mut seq = 0;
    for _ in 0..HZ {
        for _ in 0..60 {
            seq += 1;
            let mv = ViveMsg::Move { seq, direction: Vec2::X, gait: Default::default(), facing: 0.0 };
            s.send(vive, ClientMsg::Vive(mv));
        }
        s.send(vive, ClientMsg::Vive(ViveMsg::Break(CaseId(999))));
        s.step();
    }
    let mut ticks = HZ;
    while ticks < 3 * HZ && s.inbox(vive).disconnect.is_none() {
        s.step();
        ticks += 1;
    }
    let inbox = s.inbox(vive);
    assert!(inbox.refusals.contains(&Refusal::RateLimited), "told why: {:?}", &inbox.refusals[..5]);
    assert_eq!(inbox.disconnect, Some(DisconnectReason::Abuse), "sustained abuse ends in a disconnection");
    let walked = s.server.game().vive.position.distance(start);
    // One tick of walking per tick stepped, plus the banked credit and the fast-forward debt.
    let most = heist_shared::rules::WALK_SPEED * (ticks + 30 + 4) as f32 / 60.0;
    assert!(walked <= most + 1e-3, "walked {walked:.2} m in {ticks} ticks (at most {most:.2})");
}

#[test]
fn warning_spam_is_refused_and_never_reaches_vive_in_bulk() {
    let (mut s, vive, phantom) = heist_in_progress();
    s.step_until(HZ, |_| false);
    let before = s.inbox(vive).events.iter().filter(|e| matches!(e, GameEvent::Warning(_))).count();
    for _ in 0..200 {
        s.send(phantom, ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Hide)));
    }
    assert!(s.step_until(5 * HZ, |s| s.inbox(phantom).disconnect.is_some()), "the spammer is disconnected");
    s.step_until(HZ, |_| false);
    let warnings = s.inbox(vive).events.iter().filter(|e| matches!(e, GameEvent::Warning(_))).count() - before;
    assert_eq!(warnings, 3, "Vive hears the burst of three, not 200");
    let phantom_inbox = s.inbox(phantom);
    assert!(phantom_inbox.refusals.iter().all(|r| *r == Refusal::RateLimited), "{:?}", phantom_inbox.refusals);
    assert_eq!(phantom_inbox.disconnect, Some(DisconnectReason::Abuse));
    assert!(s.clients[vive].world().resource::<RenetClient>().is_connected(), "Vive stays connected");
}

#[test]
fn a_tool_pose_from_vive_moves_nothing() {
    let (mut s, vive, phantom) = heist_in_progress();
    let pose = PhantomMsg::ToolPose { position: Vec3::new(0.3, 0.4, 0.5), rotation: Quat::IDENTITY };
    s.send(vive, ClientMsg::Phantom(pose.clone()));
    assert!(s.step_until(2 * HZ, |s| !s.inbox(vive).refusals.is_empty()));
    assert_eq!(s.inbox(vive).refusals, [Refusal::WrongRole]);
    let tool = |s: &mut Session, c: usize| {
        let world = s.clients[c].world_mut();
        world.query::<&PhantomTool>().iter(world).next().copied()
    };
    assert_eq!(tool(&mut s, phantom), Some(PhantomTool::default()), "the tool did not move");
    assert_eq!(s.server.game().tool, PhantomTool::default());
    // Phantom's own pose does move it, and Vive sees it.
    s.send(phantom, ClientMsg::Phantom(pose));
    assert!(s.step_until(2 * HZ, |s| s.server.game().tool.position == Vec3::new(0.3, 0.4, 0.5)));
    let seen = (0..2 * HZ).any(|_| {
        s.step();
        tool(&mut s, vive).is_some_and(|t| t.position == Vec3::new(0.3, 0.4, 0.5))
    });
    assert!(seen, "Vive's client sees Phantom's tool where Phantom put it");
}

#[test]
fn the_vive_client_never_receives_a_guard_he_could_not_perceive_and_phantom_keeps_them_all() {
    use heist_shared::protocol::GuardView;
    let mut heist =
        heist_server::demo::Heist::start(ServerOptions::local_test(10), heist_bots::ViveStyle::Careful).unwrap();
    let guards = heist.server.game().guards.len();
    // Which guards Vive could perceive, tick by tick (the last few: what the client holds was sent a
    // round trip ago).
    let mut perceivable: std::collections::VecDeque<Vec<bool>> = std::collections::VecDeque::new();
    let (mut fewer, mut some) = (0, 0);
    for tick in 0..(150 * HZ) {
        heist.step();
        let game = heist.server.game();
        if !game.is_running() && tick > 10 * HZ {
            break;
        }
        perceivable.push_back((0..guards).map(|i| game.vive_perceives(i)).collect());
        if perceivable.len() > 12 {
            perceivable.pop_front();
        }
        let world = heist.vive.world_mut();
        let held: Vec<u16> = world.query::<&GuardView>().iter(world).map(|g| g.id.0).collect();
        for id in &held {
            assert!(
                perceivable.iter().any(|p| p[usize::from(*id)]),
                "tick {tick}: Vive's client holds guard {id}, out of his sight and earshot for {} ticks",
                perceivable.len()
            );
        }
        fewer += usize::from(held.len() < guards);
        some += usize::from(!held.is_empty());
        if tick > 2 * HZ {
            let world = heist.phantom.world_mut();
            assert_eq!(world.query::<&GuardView>().iter(world).count(), guards, "tick {tick}: Phantom holds them all");
        }
    }
    assert!(fewer > 0 && some > 0, "some guards were out of Vive's perception ({fewer} ticks), some in ({some})");
}
