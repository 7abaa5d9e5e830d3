//! Rule tests: the game core alone, no network.

use glam::Vec2;
use heist_shared::level::Level;
use heist_shared::protocol::{
    CaseId, ClientMsg, GameEvent, ItemPlace, LobbyMsg, LossReason, Phase, PhantomMsg, Refusal, Role, ServerMsg,
    VerdictOutcome, ViveMsg,
};

use super::*;

fn started(seed: u64) -> Game {
    let mut g = Game::new(Level::museum(), &GameOptions { seed, time_limit_s: None });
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
    let mut g = Game::new(Level::museum(), &GameOptions { seed: 0, time_limit_s: Some(2.0) });
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
    vive(&mut g, ViveMsg::Move { seq: 1, direction: toward, gait: Default::default(), facing: 0.0 }).unwrap();
    for _ in 0..600 {
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

