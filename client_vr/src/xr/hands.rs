//! What Vive's hands and sticks do in XR, decided from one frame's controls: the per-hand rules (grab,
//! place or drop, throw, break, another round, snap turn, running), the recentring hold, and
//! locomotion (smooth or teleport, the head's lead). Plain values in, plain values out, tested as
//! sentences; `super` reads the controllers into [`HandInput`]s and carries out what these return.

use glam::{Vec2, Vec3};
use heist_shared::protocol::{CaseId, Gait, ItemId, Phase};
use heist_shared::rules;

use super::arc::TeleportArc;
use crate::intent::Action as Do;
use crate::space;

/// Snap-turn angle, radians.
pub const SNAP_TURN: f32 = std::f32::consts::PI / 6.0;
/// How far the head may lead the body before walls hold the view back, metres.
pub const HEAD_LEASH_M: f32 = 0.6;
/// Head height below which a standing player crouches, metres.
pub const CROUCH_BELOW_M: f32 = 1.15;
/// How far a trigger is pulled to count as pulled (0..1).
pub const TRIGGER_PULLED: f32 = 0.6;
/// How far a stick is pushed sideways to snap-turn once (0..1; back under it before the next turn).
pub const SNAP_STICK: f32 = 0.7;
/// How far the off hand's stick is pushed forward to aim a teleport (0..1).
pub const TELEPORT_STICK: f32 = 0.6;
/// Seconds both grips are held with empty hands to recentre.
pub const RECENTRE_HOLD_S: f32 = 1.5;
/// Frames of a hand's positions its throwing velocity is taken over (the newest last).
pub const THROW_FRAMES: usize = 6;

/// One hand's controls this frame, as read from the controller.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HandInput {
    /// The grip is squeezed.
    pub squeeze: bool,
    /// The trigger is pulled (past [`TRIGGER_PULLED`]).
    pub trigger: bool,
    /// The stick (or trackpad), −1..1 each way.
    pub stick: Vec2,
    /// The stick was clicked this frame.
    pub click: bool,
    /// Where the hand is (its grip), world, metres.
    pub position: Vec3,
    /// Which way the hand points on the floor (unit).
    pub pointing: Vec2,
    /// Where its aim ray starts, world, metres.
    pub aim_from: Vec3,
    /// Which way its aim ray goes, world (unit).
    pub aim_along: Vec3,
}

/// What one hand remembers from frame to frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HandMemory {
    /// The grip was squeezed last frame.
    pub squeezed: bool,
    /// The trigger was pulled last frame.
    pub triggered: bool,
    /// The hand's last positions, the newest last (its throwing velocity).
    pub positions: [Vec3; THROW_FRAMES],
    /// The item in the hand.
    pub holding: Option<ItemId>,
    /// The stick last frame.
    pub stick_was: Vec2,
    /// What the empty hand would pick up if its grip closed now (shown by a highlight ring).
    pub grabbable: Option<ItemId>,
}

/// What is around a hand this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AroundHand {
    /// The session's phase.
    pub phase: Phase,
    /// The item the hand is at (nearest within reach along its pointing), if any.
    pub item: Option<ItemId>,
    /// The case the hand points at, if any.
    pub case: Option<CaseId>,
    /// Where the workbench is, once the level arrived.
    pub bench: Option<Vec2>,
    /// The server no longer has the held item in Vive's hands (delivered, secured).
    pub held_taken: bool,
}

/// What a hand does this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HandOutcome {
    /// Actions for the server, in order.
    pub actions: Vec<Do>,
    /// The off hand's stick was clicked: running toggles.
    pub toggle_running: bool,
    /// The main hand's stick snapped the view round by this angle, radians (positive: left).
    pub turn: Option<f32>,
}

/// What `input` does with a hand that remembers `memory` among `around`, `main` or the off hand, `dt`
/// seconds after the last frame; `memory` moves on to this frame.
pub fn decide_hand(
    memory: &mut HandMemory,
    input: &HandInput,
    around: &AroundHand,
    main: bool,
    dt: f32,
) -> HandOutcome {
    let mut out = HandOutcome::default();
    let held_before = memory.holding;
    memory.positions.rotate_left(1);
    memory.positions[THROW_FRAMES - 1] = input.position;
    let velocity = (input.position - memory.positions[0]) / ((THROW_FRAMES - 1) as f32 * dt.max(1e-4));
    memory.grabbable = if memory.holding.is_none() { around.item } else { None };
    let (grabbed, let_go) = (input.squeeze && !memory.squeezed, !input.squeeze && memory.squeezed);
    let (pulled, released) = (input.trigger && !memory.triggered, !input.trigger && memory.triggered);
    if grabbed
        && memory.holding.is_none()
        && let Some(item) = around.item
    {
        out.actions.push(Do::PickUp(item));
        memory.holding = Some(item);
    }
    if let_go
        && !memory.triggered
        && let Some(item) = memory.holding.take()
    {
        let at_bench = around.bench.is_some_and(|b| b.distance(space::floor(input.position)) < rules::REACH);
        out.actions.push(if at_bench { Do::Place(item) } else { Do::Drop(item) });
    }
    if pulled && matches!(around.phase, Phase::Won | Phase::Lost(_)) {
        out.actions.push(Do::Rematch);
    }
    if pulled
        && memory.holding.is_none()
        && let Some(case) = around.case
    {
        out.actions.push(Do::Break(case));
    }
    if released && let Some(item) = memory.holding.take() {
        out.actions.push(Do::Throw { item, target: throw_landing(input.position, velocity) });
    }
    memory.squeezed = input.squeeze;
    memory.triggered = input.trigger;
    out.toggle_running = input.click && !main;
    if main && input.stick.x.abs() > SNAP_STICK && memory.stick_was.x.abs() <= SNAP_STICK {
        out.turn = Some(-input.stick.x.signum() * SNAP_TURN);
    }
    // Let go of an item the server took away (delivered, secured).
    if memory.holding.is_some() && memory.holding == held_before && around.held_taken && !input.squeeze {
        memory.holding = None;
    }
    memory.stick_was = input.stick;
    out
}

/// Where a throw from `hand` (world) at `velocity` (world, m/s) lands on the floor: ballistic flight,
/// capped at the throw range.
pub fn throw_landing(hand: Vec3, velocity: Vec3) -> Vec2 {
    let g = 9.81;
    let h = hand.y.max(0.0);
    let vy = velocity.y;
    let t = (vy + (vy * vy + 2.0 * g * h).sqrt()) / g;
    let from = space::floor(hand);
    let flight = space::floor(Vec3::new(velocity.x, 0.0, velocity.z)) * t;
    from + flight.clamp_length_max(rules::THROW_RANGE)
}

/// Both grips held with empty hands for [`RECENTRE_HOLD_S`] recentre the view, once a hold: true on the
/// frame it does; `held_s` counts the hold.
pub fn hold_to_recentre(hands: &[HandMemory; 2], held_s: &mut f32, dt: f32) -> bool {
    if hands.iter().all(|h| h.squeezed && h.holding.is_none()) {
        *held_s += dt;
        if *held_s > RECENTRE_HOLD_S {
            *held_s = f32::NEG_INFINITY;
            return true;
        }
    } else {
        *held_s = 0.0;
    }
    false
}

/// How the body moves, frame to frame.
#[derive(Clone, Debug, Default)]
pub struct Moving {
    /// Where a teleport takes the body, until it is there.
    pub travel: Option<Vec2>,
    /// The sticks moved the body last frame (the room is carried along).
    pub locomoting: bool,
    /// How dark the view is (teleports), 0..0.95.
    pub fade: f32,
    /// The comfort vignette's strength (smooth motion), 0..1.
    pub vignette: f32,
    /// The teleport arc while the off hand's stick is pushed.
    pub arc: Option<TeleportArc>,
    /// Where the body was last frame.
    pub last_body: Option<Vec2>,
}

/// Where the player is this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Standing {
    /// The view's heading, radians (0 along the floor's +x).
    pub facing: f32,
    /// The head, world, metres.
    pub head: Vec3,
    /// The body, on the floor.
    pub body: Vec2,
    /// Seated play (no room crouch).
    pub seated: bool,
    /// Smooth locomotion (else teleport).
    pub smooth: bool,
    /// Running was toggled on.
    pub running: bool,
    /// Seconds since the last frame.
    pub dt: f32,
}

/// How the body moves this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// The movement intent (|m| ≤ 1).
    pub movement: Vec2,
    /// The gait.
    pub gait: Gait,
    /// How far the view is pulled back towards the body (the head led it past [`HEAD_LEASH_M`]).
    pub leash: Option<Vec2>,
}

/// Whether the off hand's stick aims a teleport.
pub fn aiming(stick: Vec2) -> bool {
    stick.y > TELEPORT_STICK
}

/// How far the room is carried with the body this frame (the sticks moved it last frame), and where the
/// body is now remembered.
pub fn carry(moving: &mut Moving, body: Vec2) -> Option<Vec2> {
    let carried = moving.last_body.filter(|_| moving.locomoting).map(|last| body - last);
    moving.last_body = Some(body);
    carried
}

/// How the off hand's `stick` moves the body at `at`; `aimed` is the teleport arc when [`aiming`].
pub fn decide_move(moving: &mut Moving, stick: Vec2, at: &Standing, aimed: Option<TeleportArc>) -> Move {
    let ahead = Vec2::new(at.facing.cos(), at.facing.sin());
    let right = Vec2::new(at.facing.sin(), -at.facing.cos());
    let gait = if !at.seated && at.head.y < CROUCH_BELOW_M {
        Gait::Crouch
    } else if at.running {
        Gait::Run
    } else {
        Gait::Walk
    };
    let mut movement = Vec2::ZERO;
    moving.locomoting = false;
    if at.smooth {
        moving.locomoting = stick.length() > 0.1;
        movement = (ahead * stick.y + right * stick.x).clamp_length_max(1.0);
        moving.vignette = movement.length();
    } else if aiming(stick) {
        // Aiming: the arc from the off hand shows where, green when the body may go there.
        if aimed.is_some() {
            moving.arc = aimed;
        }
        moving.travel = None;
        moving.fade = 0.0;
    } else if let Some(aimed) = moving.arc.take() {
        // Let go: a valid target blinks the body there (the view goes dark while the server walks it); a
        // refused one does nothing.
        if aimed.valid() {
            moving.travel = Some(aimed.landing);
            moving.fade = 0.95;
        }
    } else if let Some(target) = moving.travel {
        let d = target - at.body;
        if d.length() < 0.1 {
            moving.travel = None;
            moving.fade = 0.0;
        } else {
            movement = d.normalize();
            moving.fade = 0.85;
            moving.locomoting = true;
        }
    }
    // Walking in the room pulls the body along; walls hold the head back.
    let lead = space::floor(at.head) - at.body;
    if movement == Vec2::ZERO && lead.length() > 0.15 {
        movement = (lead / (rules::gait_speed(gait) * at.dt.max(1e-4))).clamp_length_max(1.0);
    }
    let leash = (lead.length() > HEAD_LEASH_M).then(|| lead - lead.normalize() * HEAD_LEASH_M);
    Move { movement, gait, leash }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f32 = 1.0 / 90.0;

    fn around(item: Option<u16>, case: Option<u16>) -> AroundHand {
        AroundHand {
            phase: Phase::Heist,
            item: item.map(ItemId),
            case: case.map(CaseId),
            bench: Some(Vec2::new(10.0, 0.0)),
            held_taken: false,
        }
    }

    fn hand(squeeze: bool, trigger: bool) -> HandInput {
        HandInput { squeeze, trigger, position: Vec3::new(0.0, 1.0, 0.0), ..Default::default() }
    }

    #[test]
    fn closing_the_grip_at_an_item_picks_it_up_once_and_an_empty_hand_shows_what_it_would_take() {
        let mut m = HandMemory::default();
        let out = decide_hand(&mut m, &hand(false, false), &around(Some(3), None), true, DT);
        assert!(out.actions.is_empty());
        assert_eq!(m.grabbable, Some(ItemId(3)));
        let out = decide_hand(&mut m, &hand(true, false), &around(Some(3), None), true, DT);
        assert_eq!(out.actions, [Do::PickUp(ItemId(3))]);
        assert_eq!(m.holding, Some(ItemId(3)));
        let out = decide_hand(&mut m, &hand(true, false), &around(Some(3), None), true, DT);
        assert!(out.actions.is_empty(), "held, not picked up again");
        assert_eq!(m.grabbable, None, "a full hand takes nothing");
    }

    #[test]
    fn opening_the_grip_places_a_copy_at_the_bench_and_drops_it_anywhere_else() {
        let mut m = HandMemory { squeezed: true, holding: Some(ItemId(3)), ..Default::default() };
        let out = decide_hand(&mut m, &hand(false, false), &around(None, None), true, DT);
        assert_eq!(out.actions, [Do::Drop(ItemId(3))]);
        let mut m = HandMemory { squeezed: true, holding: Some(ItemId(3)), ..Default::default() };
        let at_bench = HandInput { position: space::world(Vec2::new(10.5, 0.0), 1.0), ..hand(false, false) };
        let out = decide_hand(&mut m, &at_bench, &around(None, None), true, DT);
        assert_eq!(out.actions, [Do::Place(ItemId(3))]);
        assert_eq!(m.holding, None);
    }

    #[test]
    fn pulling_the_trigger_with_an_empty_hand_breaks_the_case_pointed_at() {
        let mut m = HandMemory::default();
        let out = decide_hand(&mut m, &hand(false, true), &around(None, Some(2)), true, DT);
        assert_eq!(out.actions, [Do::Break(CaseId(2))]);
        let out = decide_hand(&mut m, &hand(false, true), &around(None, Some(2)), true, DT);
        assert!(out.actions.is_empty(), "once a pull");
    }

    #[test]
    fn releasing_the_trigger_while_holding_throws_where_the_hand_was_swinging() {
        let mut m = HandMemory { squeezed: true, holding: Some(ItemId(5)), ..Default::default() };
        // Swing forward (−z on the world is +y on the floor) at 3 m/s with the trigger held.
        for k in 0..THROW_FRAMES {
            let p = Vec3::new(0.0, 1.2, -3.0 * DT * k as f32);
            decide_hand(&mut m, &HandInput { position: p, ..hand(true, true) }, &around(None, None), true, DT);
        }
        let p = Vec3::new(0.0, 1.2, -3.0 * DT * THROW_FRAMES as f32);
        let out = decide_hand(&mut m, &HandInput { position: p, ..hand(true, false) }, &around(None, None), true, DT);
        let [Do::Throw { item, target }] = out.actions.as_slice() else { panic!("a throw: {:?}", out.actions) };
        assert_eq!(*item, ItemId(5));
        assert!(target.y > 1.0 && target.x.abs() < 1e-3, "lands ahead of the hand: {target}");
        assert_eq!(m.holding, None);
    }

    #[test]
    fn after_a_result_a_trigger_pull_asks_for_another_round() {
        let mut m = HandMemory::default();
        let won = AroundHand { phase: Phase::Won, ..around(None, None) };
        assert_eq!(decide_hand(&mut m, &hand(false, true), &won, false, DT).actions, [Do::Rematch]);
    }

    #[test]
    fn the_main_sticks_push_sideways_snaps_once_and_the_off_sticks_click_toggles_running() {
        let mut m = HandMemory::default();
        let right = HandInput { stick: Vec2::new(0.9, 0.0), ..hand(false, false) };
        assert_eq!(decide_hand(&mut m, &right, &around(None, None), true, DT).turn, Some(-SNAP_TURN));
        assert_eq!(decide_hand(&mut m, &right, &around(None, None), true, DT).turn, None, "held: no second snap");
        let mut off = HandMemory::default();
        let click = HandInput { click: true, stick: Vec2::new(0.9, 0.0), ..hand(false, false) };
        let out = decide_hand(&mut off, &click, &around(None, None), false, DT);
        assert!(out.toggle_running && out.turn.is_none());
    }

    #[test]
    fn an_item_the_server_took_leaves_the_open_hand() {
        let mut m = HandMemory { squeezed: false, triggered: true, holding: Some(ItemId(4)), ..Default::default() };
        let taken = AroundHand { held_taken: true, ..around(None, None) };
        let out = decide_hand(&mut m, &hand(false, true), &taken, true, DT);
        assert!(out.actions.is_empty());
        assert_eq!(m.holding, None);
    }

    #[test]
    fn holding_both_empty_grips_a_second_and_a_half_recentres_once() {
        let gripping = HandMemory { squeezed: true, ..Default::default() };
        let mut held = 0.0;
        assert!(!hold_to_recentre(&[gripping; 2], &mut held, 1.0));
        assert!(hold_to_recentre(&[gripping; 2], &mut held, 0.6));
        assert!(!hold_to_recentre(&[gripping; 2], &mut held, 5.0), "once a hold");
        let full = HandMemory { holding: Some(ItemId(1)), ..gripping };
        assert!(!hold_to_recentre(&[gripping, full], &mut held, 5.0), "a full hand does not recentre");
        assert_eq!(held, 0.0);
    }

    fn standing(smooth: bool) -> Standing {
        Standing {
            facing: std::f32::consts::FRAC_PI_2,
            head: space::world(Vec2::ZERO, 1.6),
            body: Vec2::ZERO,
            seated: false,
            smooth,
            running: false,
            dt: DT,
        }
    }

    #[test]
    fn smooth_locomotion_moves_where_the_stick_points_with_the_vignette_closing() {
        let mut moving = Moving::default();
        let m = decide_move(&mut moving, Vec2::new(0.0, 1.0), &standing(true), None);
        assert!((m.movement - Vec2::Y).length() < 1e-5, "ahead is the facing: {}", m.movement);
        assert_eq!(m.gait, Gait::Walk);
        assert!(moving.locomoting && (moving.vignette - 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_low_head_crouches_unless_seated_and_running_runs() {
        let low = Standing { head: space::world(Vec2::ZERO, 1.0), ..standing(true) };
        assert_eq!(decide_move(&mut Moving::default(), Vec2::ZERO, &low, None).gait, Gait::Crouch);
        let seated = Standing { seated: true, ..low };
        assert_eq!(decide_move(&mut Moving::default(), Vec2::ZERO, &seated, None).gait, Gait::Walk);
        let running = Standing { running: true, ..standing(true) };
        assert_eq!(decide_move(&mut Moving::default(), Vec2::ZERO, &running, None).gait, Gait::Run);
    }

    #[test]
    fn a_teleport_goes_where_a_valid_arc_ended_in_the_dark_and_stops_there() {
        let mut moving = Moving::default();
        let arc = TeleportArc { points: vec![Vec3::ZERO], landing: Vec2::new(0.0, 3.0), verdict: Ok(()) };
        assert!(aiming(Vec2::new(0.0, 0.9)));
        decide_move(&mut moving, Vec2::new(0.0, 0.9), &standing(false), Some(arc));
        assert!(moving.arc.is_some() && moving.travel.is_none());
        decide_move(&mut moving, Vec2::ZERO, &standing(false), None);
        assert_eq!(moving.travel, Some(Vec2::new(0.0, 3.0)));
        assert!(moving.fade > 0.9, "the view goes dark");
        let m = decide_move(&mut moving, Vec2::ZERO, &standing(false), None);
        assert!((m.movement - Vec2::Y).length() < 1e-5 && moving.locomoting);
        let there =
            Standing { body: Vec2::new(0.0, 2.95), head: space::world(Vec2::new(0.0, 2.95), 1.6), ..standing(false) };
        let m = decide_move(&mut moving, Vec2::ZERO, &there, None);
        assert_eq!((m.movement, moving.travel, moving.fade), (Vec2::ZERO, None, 0.0));
    }

    #[test]
    fn a_head_that_leads_the_body_pulls_it_along_and_too_far_is_held_back() {
        let leaning = Standing { head: space::world(Vec2::new(0.3, 0.0), 1.6), ..standing(false) };
        let m = decide_move(&mut Moving::default(), Vec2::ZERO, &leaning, None);
        assert!(m.movement.x > 0.0 && m.leash.is_none());
        let through_a_wall = Standing { head: space::world(Vec2::new(1.0, 0.0), 1.6), ..standing(false) };
        let m = decide_move(&mut Moving::default(), Vec2::ZERO, &through_a_wall, None);
        let back = m.leash.expect("held back");
        assert!((back - Vec2::new(1.0 - HEAD_LEASH_M, 0.0)).length() < 1e-5, "{back}");
    }

    #[test]
    fn the_room_is_carried_with_the_body_only_after_the_sticks_moved_it() {
        let mut moving = Moving::default();
        assert_eq!(carry(&mut moving, Vec2::ZERO), None);
        moving.locomoting = true;
        assert_eq!(carry(&mut moving, Vec2::new(0.5, 0.0)), Some(Vec2::new(0.5, 0.0)));
        moving.locomoting = false;
        assert_eq!(carry(&mut moving, Vec2::new(1.0, 0.0)), None);
    }
}
