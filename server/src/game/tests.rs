//! Rule tests: the game core alone, no network.

use glam::Vec2;
use heist_shared::level::Level;
use heist_shared::protocol::{
    CaseId, ClientMsg, GameEvent, ItemPlace, LobbyMsg, LossReason, PhantomMsg, Phase, Refusal, Role, ServerMsg,
    VerdictOutcome, ViveMsg,
};

use super::*;

fn started(seed: u64) -> Game {
    let mut g = Game::new(Level::museum(), &GameOptions { seed, ..Default::default() });
    g.join(Role::Vive);
    g.join(Role::Phantom);
    g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    assert_eq!(g.phase, Phase::Lobby, "one ready player is not enough");
    g.apply(Role::Phantom, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    assert_eq!(g.phase, Phase::Heist);
    g
}

fn vive(g: &mut Game, m: ViveMsg) -> Result<(), Refusal> {
    g.apply(Role::Vive, &ClientMsg::Vive(m))
}

/// Teleports Vive next to a case holding a copy, breaks it and picks the copy up.
fn grab_copy(g: &mut Game, index: usize) -> ItemId {
    let item = Game::item_id(index);
    let ItemPlace::InCase(case) = g.items[index].place else { panic!("copy not in a case") };
    g.vive.position = g.cases[usize::from(case.0)].position + Vec2::new(0.0, 0.5);
    vive(g, ViveMsg::Break(case)).unwrap();
    vive(g, ViveMsg::PickUp(item)).unwrap();
    item
}

fn deliver(g: &mut Game, item: ItemId) {
    g.vive.position = g.level.workbench + Vec2::new(0.5, 0.0);
    vive(g, ViveMsg::PlaceOnWorkbench(item)).unwrap();
}

fn verdict(g: &mut Game, item: ItemId, real: bool) -> Result<(), Refusal> {
    g.apply(Role::Phantom, &ClientMsg::Phantom(PhantomMsg::Verdict { item, real }))
}

#[test]
fn the_heist_waits_for_both_players() {
    let mut g = Game::new(Level::museum(), &GameOptions::default());
    g.join(Role::Vive);
    g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    g.step(1.0);
    assert_eq!(g.phase, Phase::Lobby);
}

#[test]
fn each_target_has_exactly_one_real_copy_and_at_least_two_fakes() {
    let g = started(3);
    for t in 0..g.targets.len() {
        let copies: Vec<_> = g.items.iter().filter_map(|i| i.truth.as_ref()).filter(|c| c.target == t).collect();
        assert!(copies.len() >= 3);
        assert_eq!(copies.iter().filter(|c| c.real).count(), 1);
    }
}

#[test]
fn breaking_a_case_is_loud_and_an_intact_case_keeps_its_copy() {
    let mut g = started(1);
    let ItemPlace::InCase(case) = g.items[0].place else { panic!() };
    g.vive.position = g.cases[usize::from(case.0)].position + Vec2::new(0.0, 0.5);
    assert_eq!(vive(&mut g, ViveMsg::PickUp(Game::item_id(0))), Err(Refusal::CaseIntact));
    g.drain_outgoing().for_each(drop);
    vive(&mut g, ViveMsg::Break(case)).unwrap();
    let noisy = g.drain_outgoing().any(|o| matches!(o, Outgoing::All(ServerMsg::Event(GameEvent::Noise { .. }))));
    assert!(noisy);
    assert_eq!(vive(&mut g, ViveMsg::Break(case)), Err(Refusal::AlreadyBroken));
}

#[test]
fn vive_cannot_reach_across_the_room_or_carry_three_things() {
    let mut g = started(2);
    g.vive.position = Vec2::new(1.0, 1.0);
    assert_eq!(vive(&mut g, ViveMsg::Break(CaseId(0))), Err(Refusal::OutOfReach));
    let copies: Vec<usize> = (0..g.items.len()).filter(|&i| g.items[i].truth.is_some()).take(3).collect();
    grab_copy(&mut g, copies[0]);
    grab_copy(&mut g, copies[1]);
    let third = Game::item_id(copies[2]);
    let ItemPlace::InCase(case) = g.items[copies[2]].place else { panic!() };
    g.vive.position = g.cases[usize::from(case.0)].position;
    vive(&mut g, ViveMsg::Break(case)).unwrap();
    assert_eq!(vive(&mut g, ViveMsg::PickUp(third)), Err(Refusal::HandsFull));
}

#[test]
fn verdicts_secure_real_copies_discard_fakes_and_wrong_ones_raise_the_alarm() {
    let mut g = started(4);
    let real = (0..g.items.len()).find(|&i| g.items[i].truth.as_ref().is_some_and(|t| t.real)).unwrap();
    let fake = (0..g.items.len()).find(|&i| g.items[i].truth.as_ref().is_some_and(|t| !t.real)).unwrap();

    assert_eq!(verdict(&mut g, Game::item_id(fake), false), Err(Refusal::NotOnWorkbench));

    let f = grab_copy(&mut g, fake);
    deliver(&mut g, f);
    verdict(&mut g, f, true).unwrap();
    assert_eq!(g.alarm, 1);
    assert_eq!(g.workbench, Some(f), "a wrongly judged copy stays on the bench");
    verdict(&mut g, f, false).unwrap();
    assert_eq!(g.items[fake].place, ItemPlace::Discarded);

    let r = grab_copy(&mut g, real);
    deliver(&mut g, r);
    g.drain_outgoing().for_each(drop);
    verdict(&mut g, r, true).unwrap();
    assert_eq!(g.items[real].place, ItemPlace::Secured);
    let outcome = g.drain_outgoing().find_map(|o| match o {
        Outgoing::All(ServerMsg::Event(GameEvent::Verdict { outcome, .. })) => Some(outcome),
        _ => None,
    });
    assert_eq!(outcome, Some(VerdictOutcome::Secured));
}

#[test]
fn securing_every_real_copy_wins() {
    let mut g = started(5);
    let reals: Vec<usize> = (0..g.items.len()).filter(|&i| g.items[i].truth.as_ref().is_some_and(|t| t.real)).collect();
    for i in reals {
        let id = grab_copy(&mut g, i);
        deliver(&mut g, id);
        verdict(&mut g, id, true).unwrap();
    }
    assert_eq!(g.phase, Phase::Won);
}

#[test]
fn three_wrong_verdicts_lock_the_museum_down() {
    let mut g = started(6);
    let fake = (0..g.items.len()).find(|&i| g.items[i].truth.as_ref().is_some_and(|t| !t.real)).unwrap();
    let f = grab_copy(&mut g, fake);
    deliver(&mut g, f);
    for _ in 0..3 {
        verdict(&mut g, f, true).unwrap();
    }
    assert_eq!(g.phase, Phase::Lost(LossReason::Alarm));
}

#[test]
fn the_timer_ends_the_heist() {
    let mut g = Game::new(Level::museum(), &GameOptions { seed: 0, time_limit_s: Some(2.0), ..Default::default() });
    g.join(Role::Vive);
    g.join(Role::Phantom);
    g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    g.apply(Role::Phantom, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    g.vive.position = g.level.exit; // out of every guard's way
    for _ in 0..200 {
        g.step(1.0 / 60.0);
    }
    assert_eq!(g.phase, Phase::Lost(LossReason::Time));
}

#[test]
fn walking_into_a_guard_gets_vive_caught() {
    let mut g = started(7);
    let guard_at = g.guards[0].position;
    g.vive.position = guard_at + Vec2::new(2.0, 0.0);
    let toward = (guard_at - g.vive.position).normalize();
    for seq in 1..=600 {
        vive(&mut g, ViveMsg::Move { seq, direction: toward, gait: Default::default(), facing: 0.0 }).unwrap();
        g.step(1.0 / 60.0);
        if g.phase != Phase::Heist {
            break;
        }
    }
    assert_eq!(g.phase, Phase::Lost(LossReason::Caught));
}

#[test]
fn the_same_seed_gives_the_same_session() {
    let (a, b) = (started(9), started(9));
    let places = |g: &Game| g.items.iter().map(|i| format!("{:?}", i.place)).collect::<Vec<_>>();
    assert_eq!(places(&a), places(&b));
    let reals = |g: &Game| g.items.iter().map(|i| i.truth.as_ref().is_some_and(|t| t.real)).collect::<Vec<_>>();
    assert_eq!(reals(&a), reals(&b));
    assert_ne!(reals(&a), reals(&started(10)), "another seed shuffles the copies");
}

fn walk(seq: u32, direction: Vec2) -> ViveMsg {
    ViveMsg::Move { seq, direction, gait: Default::default(), facing: 0.0 }
}

/// Where the body would be after `n` ticks of walking east from `from` (open floor).
fn east_of(from: Vec2, n: u32) -> Vec2 {
    from + Vec2::X * heist_shared::rules::WALK_SPEED * TICK_S * n as f32
}

#[test]
fn each_input_moves_the_body_one_tick_and_no_input_stands_still() {
    let mut g = started(3);
    let start = g.vive.position;
    vive(&mut g, walk(1, Vec2::X)).unwrap();
    g.step(TICK_S);
    assert!(g.vive.position.distance(east_of(start, 1)) < 1e-5);
    assert_eq!(g.vive.last_input_seq, 1);
    // No new input: the body does not keep walking on an old one.
    for _ in 0..10 {
        g.step(TICK_S);
    }
    assert!(g.vive.position.distance(east_of(start, 1)) < 1e-5);
    // A repeated or older input is ignored.
    vive(&mut g, walk(1, Vec2::X)).unwrap();
    g.step(TICK_S);
    assert!(g.vive.position.distance(east_of(start, 1)) < 1e-5);
}

#[test]
fn inputs_bunched_by_the_network_are_all_applied_in_order() {
    let mut g = started(3);
    let start = g.vive.position;
    // Three ticks without input (a resend in flight), then six inputs at once.
    for _ in 0..3 {
        g.step(TICK_S);
    }
    for seq in 1..=6 {
        vive(&mut g, walk(seq, Vec2::X)).unwrap();
    }
    for _ in 0..4 {
        g.step(TICK_S);
    }
    assert_eq!(g.vive.last_input_seq, 6, "caught up on banked ticks");
    assert!(g.vive.position.distance(east_of(start, 6)) < 1e-4, "exactly six ticks of walking");
}

#[test]
fn sending_faster_than_the_tick_rate_gains_no_speed() {
    let mut g = started(3);
    let start = g.vive.position;
    let mut seq = 0;
    for _ in 0..60 {
        for _ in 0..3 {
            seq += 1;
            vive(&mut g, walk(seq, Vec2::X)).unwrap();
        }
        g.step(TICK_S);
    }
    let walked = g.vive.position.distance(start);
    let one_second = heist_shared::rules::WALK_SPEED;
    assert!(walked <= one_second * (60.0 + MAX_MOVE_CREDIT as f32) / 60.0 + 1e-3, "walked {walked} m in a second");
    assert!(g.vive.inputs.len() <= MAX_QUEUED_INPUTS);
}

#[test]
fn an_action_applies_the_inputs_sent_before_it_first() {
    let mut g = started(3);
    let case = g.cases[0].position;
    // Put the body 2 m from the case; the queued inputs bring it within reach. Their ticks passed while
    // they were late (banked credit), as when the network bunches them.
    let dir = Vec2::X;
    g.vive.position = case - dir * (heist_shared::rules::REACH + 0.05);
    for _ in 0..10 {
        g.step(TICK_S);
    }
    let start = g.vive.position;
    for seq in 1..=10 {
        vive(&mut g, walk(seq, dir)).unwrap();
    }
    assert_eq!(
        vive(&mut g, ViveMsg::Break(heist_shared::protocol::CaseId(0))),
        Ok(()),
        "in reach after the queued steps"
    );
    assert_eq!(g.vive.last_input_seq, 10);
    assert!(g.vive.position.distance(east_of(start, 10)) < 1e-4);
}

#[test]
fn actions_cannot_fast_forward_vive_past_his_move_credit() {
    // The speed hack: every tick, a second's worth of moves and an action (even a refused one) to
    // fast-forward them. In the widest room, walking east, with room for far more than allowed.
    let mut g = started(3);
    let room = g.level.rooms.iter().max_by(|a, b| (a.max.x - a.min.x).total_cmp(&(b.max.x - b.min.x))).unwrap().clone();
    let start = Vec2::new(room.min.x + 0.6, room.centre().y);
    assert!(room.max.x - 0.6 - start.x > 5.0, "the room leaves 5 m to walk");
    g.vive.position = start;
    let mut seq = 0;
    for _ in 0..60 {
        for _ in 0..60 {
            seq += 1;
            vive(&mut g, walk(seq, Vec2::X)).unwrap();
        }
        let _ = vive(&mut g, ViveMsg::Break(heist_shared::protocol::CaseId(999)));
        g.step(TICK_S);
    }
    assert_eq!(g.phase, Phase::Heist);
    let walked = g.vive.position.x - start.x;
    let most = (60 + MAX_MOVE_CREDIT + MAX_MOVE_DEBT) as f32 * heist_shared::rules::WALK_SPEED * TICK_S;
    assert!(walked <= most + 1e-3, "walked {walked:.2} m in a second (at most {most:.2})");
}

#[test]
fn fast_forwarded_running_is_heard() {
    let mut g = started(3);
    // Half a second banked, then half a second of running applied at once by an action.
    for _ in 0..30 {
        g.step(TICK_S);
    }
    g.drain_outgoing().for_each(drop);
    for seq in 1..=30 {
        let run = ViveMsg::Move { seq, direction: Vec2::X, gait: heist_shared::protocol::Gait::Run, facing: 0.0 };
        vive(&mut g, run).unwrap();
    }
    let _ = vive(&mut g, ViveMsg::Break(heist_shared::protocol::CaseId(999)));
    assert_eq!(g.vive.last_input_seq, 30);
    let footsteps = g
        .drain_outgoing()
        .filter(|o| {
            matches!(
                o,
                Outgoing::All(ServerMsg::Event(GameEvent::Noise {
                    kind: heist_shared::protocol::NoiseKind::Footsteps,
                    ..
                }))
            )
        })
        .count();
    assert!(footsteps >= 1, "half a second of running makes footsteps");
}

#[test]
fn only_phantom_moves_the_tool() {
    let mut g = started(3);
    let pose = PhantomMsg::ToolPose { position: glam::Vec3::new(0.1, 0.2, 0.3), rotation: glam::Quat::IDENTITY };
    assert_eq!(g.apply(Role::Vive, &ClientMsg::Phantom(pose.clone())), Err(Refusal::WrongRole));
    assert_eq!(g.tool, Default::default(), "Vive's pose moved nothing");
    g.apply(Role::Phantom, &ClientMsg::Phantom(pose)).unwrap();
    assert_eq!(g.tool.position, glam::Vec3::new(0.1, 0.2, 0.3));
}

#[test]
fn a_warning_reaches_vive_and_phantom_hears_it_went_out() {
    use heist_shared::protocol::WarningKind;
    let mut g = started(3);
    g.drain_outgoing().for_each(drop);
    g.apply(Role::Phantom, &ClientMsg::Phantom(PhantomMsg::Warn(WarningKind::Hide))).unwrap();
    let sent: Vec<Outgoing> = g.drain_outgoing().collect();
    assert!(
        matches!(sent[..], [Outgoing::All(ServerMsg::Event(GameEvent::Warning(WarningKind::Hide)))]),
        "one message, to both players: {sent:?}"
    );
}

/// A heist under way with `options`, Vive waiting at the exit (out of the guards' way).
fn waiting_at_the_exit(options: &GameOptions) -> Game {
    let mut g = Game::new(Level::museum(), options);
    g.join(Role::Vive);
    g.join(Role::Phantom);
    g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    g.apply(Role::Phantom, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
    g.vive.position = g.level.exit;
    g
}

/// A heist started with a short clock and run out on time (Vive waits at the exit).
fn lost_on_time(seed: u64, idle_end_s: Option<f32>) -> Game {
    let mut g = waiting_at_the_exit(&GameOptions { seed, time_limit_s: Some(1.0), idle_end_s, ..Default::default() });
    for _ in 0..90 {
        g.step(TICK_S);
    }
    assert_eq!(g.phase, Phase::Lost(LossReason::Time));
    g
}

fn events(g: &mut Game) -> Vec<GameEvent> {
    g.drain_outgoing()
        .filter_map(|o| match o {
            Outgoing::All(ServerMsg::Event(e)) => Some(e),
            _ => None,
        })
        .collect()
}

#[test]
fn both_players_hear_who_joins_and_who_leaves_and_how() {
    let mut g = Game::new(Level::museum(), &GameOptions::default());
    g.join(Role::Vive);
    g.join(Role::Phantom);
    g.leave(Role::Vive, true);
    g.leave(Role::Phantom, false);
    assert_eq!(
        events(&mut g),
        vec![
            GameEvent::Joined(Role::Vive),
            GameEvent::Joined(Role::Phantom),
            GameEvent::Left { role: Role::Vive, dropped: true },
            GameEvent::Left { role: Role::Phantom, dropped: false },
        ]
    );
}

#[test]
fn a_rematch_starts_a_new_round_on_a_new_seed_once_both_ask() {
    let mut g = lost_on_time(5, None);
    let first_seed = g.seed;
    g.vive.last_input_seq = 777;
    events(&mut g);
    let rematch = ClientMsg::Lobby(LobbyMsg::Rematch);
    g.apply(Role::Vive, &rematch).unwrap();
    g.apply(Role::Vive, &rematch).unwrap(); // asking twice is asking once
    assert!(!g.is_running(), "one player's wish is not enough");
    g.apply(Role::Phantom, &rematch).unwrap();
    assert_eq!(g.phase, Phase::Heist, "both asked: the next round is on");
    assert_eq!(g.round, 2);
    assert_eq!(g.seed, next_round_seed(first_seed));
    assert_ne!(g.seed, first_seed);
    assert_eq!(g.present, (true, true), "same players");
    assert_eq!(g.vive.last_input_seq, 777, "Vive's move numbers carry on");
    assert_eq!(g.vive.position, g.level.vive_spawn);
    assert!(g.time_left_s > 0.5 && g.time_left_s <= 1.0, "the options carry over: {}", g.time_left_s);
    let out: Vec<Outgoing> = g.drain_outgoing().collect();
    let said: Vec<&GameEvent> = out
        .iter()
        .filter_map(|o| match o {
            Outgoing::All(ServerMsg::Event(e)) => Some(e),
            _ => None,
        })
        .collect();
    assert_eq!(
        said,
        vec![
            &GameEvent::RematchAsked(Role::Vive),
            &GameEvent::RematchAsked(Role::Phantom),
            &GameEvent::RoundStarted(2),
            &GameEvent::PhaseChanged(Phase::Heist)
        ]
    );
    assert!(
        out.iter().any(|o| matches!(o, Outgoing::To(Role::Phantom, ServerMsg::Briefings(b)) if b.len() == 3)),
        "Phantom is briefed on the new round's copies"
    );
    // The new round's copies differ from the first round's: which is real follows the new seed.
    let again = Game::new(Level::museum(), &GameOptions { seed: first_seed, ..Default::default() });
    let briefing = |g: &Game| g.targets.iter().map(|t| t.briefing.text.clone()).collect::<Vec<_>>();
    assert_ne!(briefing(&g), briefing(&again));
}

#[test]
fn a_hosted_session_with_a_secret_seed_draws_each_next_round_afresh() {
    // The host reads round 1's seed in his log when it ends: round 2's must not follow from it.
    let mut seeds = Vec::new();
    for _ in 0..2 {
        let options = GameOptions { seed: 5, time_limit_s: Some(1.0), random_rounds: true, ..Default::default() };
        let mut g = Game::new(Level::museum(), &options);
        g.join(Role::Vive);
        g.join(Role::Phantom);
        g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
        g.apply(Role::Phantom, &ClientMsg::Lobby(LobbyMsg::Ready)).unwrap();
        for _ in 0..90 {
            g.step(TICK_S);
        }
        g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Rematch)).unwrap();
        g.apply(Role::Phantom, &ClientMsg::Lobby(LobbyMsg::Rematch)).unwrap();
        assert_eq!(g.round, 2);
        assert_ne!(g.seed, next_round_seed(5));
        seeds.push(g.seed);
    }
    assert_ne!(seeds[0], seeds[1], "two sessions from the same first seed part ways");
}

#[test]
fn a_rematch_waits_for_a_partner_who_left_and_forgets_his_wish() {
    let mut g = lost_on_time(6, None);
    let rematch = ClientMsg::Lobby(LobbyMsg::Rematch);
    g.apply(Role::Phantom, &rematch).unwrap();
    g.leave(Role::Phantom, false);
    g.apply(Role::Vive, &rematch).unwrap();
    assert!(!g.is_running(), "Phantom is gone");
    g.join(Role::Phantom);
    g.step(TICK_S);
    assert!(!g.is_running(), "a returning player has not asked again yet");
    g.apply(Role::Phantom, &rematch).unwrap();
    assert_eq!((g.phase, g.round), (Phase::Heist, 2));
}

#[test]
fn another_round_cannot_be_asked_mid_heist() {
    let mut g = started(8);
    let asked = g.apply(Role::Vive, &ClientMsg::Lobby(LobbyMsg::Rematch));
    assert_eq!(asked, Err(Refusal::WrongPhase(Phase::Heist)));
}

#[test]
fn a_session_nobody_continues_warns_a_minute_before_it_closes() {
    let mut g = lost_on_time(9, Some(90.0));
    events(&mut g);
    let mut warned_at = None;
    let mut t = 0.0;
    while !g.closed && t < 200.0 {
        g.step(0.5);
        t += 0.5;
        if warned_at.is_none() && events(&mut g).contains(&GameEvent::EndingSoon(60)) {
            warned_at = Some(t);
        }
    }
    assert_eq!(warned_at, Some(30.0), "warned 60 s before the 90 s limit");
    assert!(g.closed && (89.0..=91.0).contains(&t), "closed after {t} s");
}

#[test]
fn a_rematch_resets_the_idle_clock_and_an_empty_finished_session_closes_at_once() {
    let mut g = lost_on_time(10, Some(90.0));
    for _ in 0..100 {
        g.step(0.5);
    }
    let rematch = ClientMsg::Lobby(LobbyMsg::Rematch);
    g.apply(Role::Vive, &rematch).unwrap();
    g.apply(Role::Phantom, &rematch).unwrap();
    assert_eq!(g.idle_s(), 0.0);
    assert!(!g.closed);
    let mut g = lost_on_time(11, None);
    g.leave(Role::Vive, false);
    g.step(TICK_S);
    assert!(!g.closed, "Phantom is still there");
    g.leave(Role::Phantom, false);
    g.step(TICK_S);
    assert!(g.closed, "nobody is left after the result");
    // A dropped player's seat is kept: the finished session waits for them, then closes.
    let mut g = lost_on_time(12, None);
    g.leave(Role::Vive, false);
    g.leave(Role::Phantom, true);
    g.step(TICK_S);
    assert!(!g.closed, "Phantom's seat is kept for a rematch");
    step_for(&mut g, rules::SEAT_HOLD_S);
    assert!(g.closed, "Phantom did not come back");
}

#[test]
fn a_lobby_waits_for_its_players_but_not_forever_once_they_all_went() {
    let mut g = Game::new(Level::museum(), &GameOptions { idle_end_s: Some(10.0), ..Default::default() });
    for _ in 0..100 {
        g.step(0.5);
    }
    assert!(!g.closed, "nobody came yet: the host waits");
    g.join(Role::Vive);
    g.leave(Role::Vive, false);
    for _ in 0..21 {
        g.step(0.5);
    }
    assert!(g.closed);
}

fn step_for(g: &mut Game, seconds: f32) {
    for _ in 0..(seconds / TICK_S).ceil() as u32 {
        g.step(TICK_S);
    }
}

fn sent_to(g: &mut Game, role: Role) -> Vec<ServerMsg> {
    g.drain_outgoing()
        .filter_map(|o| match o {
            Outgoing::To(r, msg) if r == role => Some(msg),
            _ => None,
        })
        .collect()
}

#[test]
fn a_dropped_player_pauses_the_heist_and_the_timer_and_guards_stand_still() {
    let mut g = started(21);
    step_for(&mut g, 1.0);
    let (left, elapsed) = (g.time_left_s, g.elapsed_s);
    let guards: Vec<Vec2> = g.guards.iter().map(|gd| gd.position).collect();
    g.leave(Role::Phantom, true);
    assert!(g.is_paused() && g.is_seat_kept(Role::Phantom));
    step_for(&mut g, 30.0);
    assert_eq!((g.time_left_s, g.elapsed_s), (left, elapsed), "the heist clock stood still");
    assert_eq!(g.guards.iter().map(|gd| gd.position).collect::<Vec<_>>(), guards, "no guard moved");
    assert_eq!(g.phase, Phase::Heist);
    assert!((g.seat_kept_for_s(Role::Phantom) - 30.0).abs() < 0.1);
    // Vive's moves are acknowledged and dropped: he stands; his actions wait.
    let at = g.vive.position;
    vive(&mut g, walk(1, Vec2::X)).unwrap();
    step_for(&mut g, 0.5);
    assert_eq!((g.vive.position, g.vive.last_input_seq), (at, 1));
    assert_eq!(vive(&mut g, ViveMsg::Break(CaseId(0))), Err(Refusal::Paused));
    g.resume(Role::Phantom);
    assert!(!g.is_paused() && !g.is_seat_kept(Role::Phantom));
    assert!(events(&mut g).contains(&GameEvent::Resumed(Role::Phantom)));
    step_for(&mut g, 1.0);
    assert!(g.time_left_s < left, "the clock runs again");
}

#[test]
fn a_seat_not_taken_back_within_the_hold_loses_the_heist_as_abandoned() {
    let mut g = started(22);
    g.leave(Role::Vive, true);
    step_for(&mut g, rules::SEAT_HOLD_S - 1.0);
    assert_eq!(g.phase, Phase::Heist, "still kept");
    step_for(&mut g, 1.5);
    assert_eq!(g.phase, Phase::Lost(LossReason::Abandoned));
    assert!(!g.is_seat_kept(Role::Vive));
    let heard = events(&mut g);
    let gave_up = heard.iter().position(|e| *e == GameEvent::GaveUp(Role::Vive)).expect("the partner is told");
    let lost = heard.iter().position(|e| *e == GameEvent::PhaseChanged(Phase::Lost(LossReason::Abandoned)));
    assert!(lost > Some(gave_up), "gave up, then lost: {heard:?}");
}

#[test]
fn a_seat_left_on_purpose_is_not_kept_and_the_heist_waits_less_for_a_newcomer() {
    let mut g = started(23);
    g.leave(Role::Phantom, false);
    assert!(!g.is_seat_kept(Role::Phantom) && g.is_paused());
    step_for(&mut g, ABANDON_GRACE_S + 0.5);
    assert_eq!(g.phase, Phase::Lost(LossReason::Abandoned));
}

#[test]
fn a_phantom_back_in_a_running_heist_gets_the_briefings_and_the_copy_on_the_bench() {
    let mut g = started(24);
    let item = grab_copy(&mut g, 0);
    deliver(&mut g, item);
    g.leave(Role::Phantom, true);
    g.drain_outgoing().for_each(drop);
    g.resume(Role::Phantom);
    let got = sent_to(&mut g, Role::Phantom);
    let caught_up = matches!(&got[..], [ServerMsg::Briefings(b), ServerMsg::Workbench(c)]
        if b.len() == g.targets.len() && c.item == item);
    assert!(caught_up, "{got:?}");
    assert!(verdict(&mut g, item, true).is_ok(), "and can judge it");
    // In the lobby there is nothing to catch up on.
    let mut lobby = Game::new(Level::museum(), &GameOptions::default());
    lobby.join(Role::Phantom);
    assert!(sent_to(&mut lobby, Role::Phantom).is_empty());
}

#[test]
fn a_vive_back_numbers_his_moves_afresh_and_they_count() {
    let mut g = started(25);
    for seq in 1..=200 {
        vive(&mut g, walk(seq, Vec2::ZERO)).unwrap();
        g.step(TICK_S);
    }
    assert_eq!(g.vive.last_input_seq, 200);
    g.leave(Role::Vive, true);
    g.resume(Role::Vive);
    assert_eq!(g.vive.last_input_seq, 0, "the new connection's numbering starts over");
    let at = g.vive.position;
    vive(&mut g, walk(1, Vec2::X)).unwrap();
    g.step(TICK_S);
    assert!(g.vive.position.x > at.x, "move 1 of the new connection moved him");
}

#[test]
fn a_drain_lets_a_running_heist_finish_then_closes_and_closes_a_lobby_at_once() {
    // A heist under way goes on, its players told once; its result closes the session (no rematch).
    let mut g = waiting_at_the_exit(&GameOptions { seed: 3, time_limit_s: Some(2.0), ..Default::default() });
    let _ = events(&mut g);
    g.drain(600);
    g.drain(600);
    assert_eq!(events(&mut g), vec![GameEvent::ServerClosing { within_s: 600 }], "told once");
    step_for(&mut g, 1.0);
    assert_eq!(g.phase, Phase::Heist, "the heist goes on");
    assert!(!g.closed);
    step_for(&mut g, 1.5);
    assert_eq!(g.phase, Phase::Lost(LossReason::Time));
    assert!(g.closed, "after the result the draining session closes at once");

    // A lobby closes at the next step.
    let mut lobby = Game::new(Level::museum(), &GameOptions::default());
    lobby.join(Role::Vive);
    lobby.drain(600);
    lobby.step(TICK_S);
    assert!(lobby.closed);
}

/// Steps until `found` picks an event out (at most `seconds`), teleporting nobody.
fn step_until_event<T>(g: &mut Game, seconds: f32, mut found: impl FnMut(&GameEvent) -> Option<T>) -> Option<T> {
    for _ in 0..(seconds / TICK_S).ceil() as u32 {
        g.step(TICK_S);
        if let Some(hit) = events(g).iter().find_map(&mut found) {
            return Some(hit);
        }
    }
    None
}

/// A corner of the workshop, out of every guard's sight and hearing at the start.
const HIDEOUT: Vec2 = Vec2::new(1.0, 15.0);

#[test]
fn a_guard_who_sees_vive_radios_and_the_two_others_split_up_to_search_the_rooms_around() {
    use heist_shared::protocol::RadioAbout;
    let mut g = started(7);
    // Bruno is at the east end of the west gallery, within radio range of both others (Clara at the
    // west end of her round, Dmitri at the north end of his), and Vive stands in plain sight three
    // metres in front of him.
    g.guards[0].position = Vec2::new(26.0, 5.0);
    let bruno = &g.guards[0];
    g.vive.position = bruno.position + Vec2::from_angle(bruno.facing) * 3.0;
    let call = step_until_event(&mut g, 10.0, |e| match e {
        GameEvent::Radio { guard, about: RadioAbout::Sighting, at, answering, .. } => {
            Some((*guard, *at, answering.clone()))
        }
        _ => None,
    });
    let (caller, seen_at, answering) = call.expect("Bruno radios once he is sure");
    assert_eq!(caller, g.guards[0].id);
    let mut others = [&g.guards[1], &g.guards[2]];
    others.sort_by(|a, b| a.position.distance(seen_at).total_cmp(&b.position.distance(seen_at)));
    assert_eq!(answering, others.map(|o| o.id).to_vec(), "both others are in range, nearest the spot first");
    g.vive.position = HIDEOUT; // gone
    let expected = heist_shared::level::patrol::search_spots(&g.nav, seen_at, guard::SEARCH_SPOTS);
    assert!(expected.len() >= 3, "the spot and the rooms next to it: {expected:?}");
    let delay = g.tuning.radio_delay_s;
    step_for(&mut g, delay + 0.5);
    let mut first_spots = Vec::new();
    for i in [1, 2] {
        let guard::GuardState::Search { spots, next: 0, .. } = &g.guards[i].state else {
            panic!("{} answers the call: {:?}", g.guards[i].name, g.guards[i].state)
        };
        assert_eq!(g.guards[i].alert, heist_shared::protocol::GuardAlert::Searching);
        assert!(spots.iter().all(|s| expected.contains(s)), "{spots:?} are around {seen_at:?}");
        first_spots.push(spots[0]);
    }
    assert_ne!(first_spots[0], first_spots[1], "the searchers split up");
    let rooms: std::collections::BTreeSet<_> = first_spots.iter().filter_map(|s| g.nav.room_at(*s)).collect();
    assert_eq!(rooms.len(), 2, "they search two different rooms first: {first_spots:?}");
    // Each walks to his first spot and looks around there.
    let mut reached = [false; 2];
    for _ in 0..(40.0 / TICK_S) as u32 {
        g.step(TICK_S);
        for (k, i) in [1, 2].into_iter().enumerate() {
            reached[k] |= g.guards[i].position.distance(first_spots[k]) < 1.0;
        }
    }
    assert_eq!(reached, [true, true], "both searchers got to their first spot");
    assert_eq!(g.phase, Phase::Heist, "nobody found Vive in his hideout");
}

#[test]
fn a_guard_who_finds_a_broken_case_raises_the_alarm_and_radios_the_others_to_search_around_it() {
    use heist_shared::protocol::RadioAbout;
    let mut g = started(7);
    let case = g.level.cases.iter().position(|c| c.id == "west_2").expect("the museum has west_2");
    let at = g.cases[case].position;
    g.vive.position = at + Vec2::new(0.0, 0.5);
    vive(&mut g, ViveMsg::Break(CaseId(case as u16))).unwrap();
    g.vive.position = HIDEOUT; // broke it and slipped away unseen
    assert_eq!(g.alarm, 0, "breaking alone does not raise the alarm");
    let mut alarm = None;
    let call = step_until_event(&mut g, 30.0, |e| match e {
        GameEvent::Alarm(level) => {
            alarm = Some(*level);
            None
        }
        GameEvent::Radio { about: RadioAbout::Evidence, at, .. } => Some(*at),
        _ => None,
    });
    assert_eq!(call, Some(at), "a guard came to the noise, found the broken case and radioed about it");
    assert_eq!(alarm, Some(1), "the alarm went up with the report");
    assert_eq!(g.alarm, 1);
    assert!(g.cases[case].reported, "reported once");
    // The alarm changed the patrols: a guard whose round missed every room holding a target now passes one.
    let hot = g.hot_rooms();
    for (i, guard) in g.guards.iter().enumerate() {
        let rooms: Vec<_> = guard.route.iter().filter_map(|p| g.nav.room_at(*p)).collect();
        assert!(
            rooms.iter().any(|r| hot.contains(r)),
            "guard {i} ({}) patrols a hot room: {rooms:?} vs {hot:?}",
            guard.name
        );
    }
    // A second broken case found does not raise it past the tuning's cap.
    let other = g.level.cases.iter().position(|c| c.id == "west_3").expect("west_3");
    g.cases[other].broken = true;
    step_for(&mut g, 60.0);
    assert_eq!(g.alarm, g.tuning.evidence_alarm_cap, "evidence raises the alarm at most to its cap");
}
