//! Spatial sound for Vive (kira through `heist_audio`): footsteps, glass, thuds, barks and the alarm,
//! placed around the listener at the predicted body, turned with the view.

use bevy::prelude::*;
use glam::Vec2;
use heist_audio::{AudioEngine, AudioSettings};
use heist_shared::protocol::{GameEvent, GuardAlert, GuardView, NoiseKind, Phase, Stance, ViveAvatar};

use crate::client::{Happened, ViveState, ViveSystems};
use crate::flight;
use crate::intent::Intent;
use crate::space;

/// Farthest a footstep is played from, metres.
pub const STEP_RANGE_M: f32 = 20.0;
/// Seconds between repeats of the alarm while it is raised.
pub const ALARM_EVERY_S: f32 = 3.0;

/// Starts the engine and adds the sound systems.
pub fn add(app: &mut App, settings: &AudioSettings) -> Result<(), heist_audio::AudioError> {
    let engine = AudioEngine::new(settings)?;
    app.insert_non_send(engine).init_resource::<Steps>().add_systems(Update, play.in_set(ViveSystems::Present));
    Ok(())
}

/// Most thuds waiting for their thrown item to land (older ones are played at once).
const MAX_PENDING_THUDS: usize = 8;

#[derive(Resource, Default)]
struct Steps {
    guards: Vec<(u16, Vec2)>,
    own: Option<Vec2>,
    alarm_s: f32,
    /// Thuds of thrown items still in the air: (clock time it lands, where).
    thuds: Vec<(f64, Vec2)>,
}

#[allow(clippy::too_many_arguments)]
fn play(
    mut happened: MessageReader<Happened>,
    mut audio: NonSendMut<AudioEngine>,
    mut steps: ResMut<Steps>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    guards: Query<&GuardView>,
    avatar: Query<&ViveAvatar>,
    time: Res<Time>,
) {
    let Some(me) = state.body() else { return };
    let ears = space::EYE_HEIGHT_M;
    let at = |p: Vec2, h: f32| space::listener_offset(me, intent.facing, ears, p, h);
    for Happened(e) in happened.read() {
        match e {
            GameEvent::Noise { kind: NoiseKind::Glass, position, .. } => audio.glass(at(*position, 1.2)),
            GameEvent::Noise { kind: NoiseKind::Thud, position, .. } => {
                // The server lands a throw at once; it is drawn flying there, so it is heard landing then.
                if steps.thuds.len() == MAX_PENDING_THUDS {
                    let (_, p) = steps.thuds.remove(0);
                    audio.thud(at(p, 0.0));
                }
                let lands = time.elapsed_secs_f64() + flight::flight_time_s(position.distance(me)) as f64;
                steps.thuds.push((lands, *position));
            }
            GameEvent::Noise { kind: NoiseKind::Alarm, position, .. } => audio.alarm(at(*position, 2.8)),
            GameEvent::GuardAlert { alert, position, .. }
                if matches!(alert, GuardAlert::Suspicious | GuardAlert::Chasing) =>
            {
                audio.play_at(
                    heist_audio::synth::bark(*alert == GuardAlert::Chasing),
                    at(*position, 1.7),
                    "guard bark",
                );
            }
            _ => {}
        }
    }
    let now = time.elapsed_secs_f64();
    while let Some(i) = steps.thuds.iter().position(|(lands, _)| *lands <= now) {
        let (_, p) = steps.thuds.remove(i);
        audio.thud(at(p, 0.0));
    }
    // A step every 0.7 m a guard walks, when near enough to hear.
    for g in &guards {
        let slot = match steps.guards.iter().position(|(id, _)| *id == g.id.0) {
            Some(i) => i,
            None => {
                steps.guards.push((g.id.0, g.position));
                steps.guards.len() - 1
            }
        };
        let last = steps.guards[slot].1;
        if g.position.distance(last) > 0.7 {
            steps.guards[slot].1 = g.position;
            if g.position.distance(me) < STEP_RANGE_M {
                audio.footstep(at(g.position, 0.0), 0.6, "guard footstep");
            }
        }
    }
    // Vive's own steps, soft unless running.
    if let Ok(v) = avatar.single() {
        let last = *steps.own.get_or_insert(me);
        if me.distance(last) > 0.7 {
            steps.own = Some(me);
            let loud = match v.stance {
                Stance::Crouching => 0.08,
                Stance::Running => 0.5,
                Stance::Standing => 0.2,
            };
            audio.footstep(at(me, 0.0), loud, "own footstep");
        }
    }
    // The alarm keeps ringing while raised.
    if state.alarm > 0 && state.phase == Phase::Heist {
        steps.alarm_s += time.delta_secs();
        if steps.alarm_s > ALARM_EVERY_S
            && let Some(level) = state.level.as_ref()
        {
            steps.alarm_s = 0.0;
            audio.alarm(at(level.workbench, 2.8));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_audio::{AudioOutput, SpatialMode};
    use heist_shared::level::WallSet;

    fn energy(frames: &[(f32, f32)]) -> (f32, f32) {
        frames.iter().fold((0.0, 0.0), |(l, r), f| (l + f.0 * f.0, r + f.1 * f.1))
    }

    /// An app with the sound system, memory output and Vive at the origin facing `facing`.
    fn listener(facing: f32) -> App {
        let mut app = App::new();
        app.add_plugins(MinimalPlugins).add_message::<Happened>();
        let state = ViveState {
            predictor: Some(crate::predict::Predictor::new(WallSet::default(), Vec2::ZERO)),
            ..Default::default()
        };
        app.insert_resource(state).insert_resource(Intent { facing, ..Default::default() });
        let settings = AudioSettings { output: AudioOutput::Manual, spatial: SpatialMode::Hrtf, ..Default::default() };
        add(&mut app, &settings).expect("audio starts");
        app
    }

    /// Glass breaking at `glass` heard by Vive at the origin facing `facing`: (left, right) energy.
    fn hear_glass(facing: f32, glass: Vec2) -> (f32, f32) {
        let mut app = listener(facing);
        app.world_mut().write_message(Happened(GameEvent::Noise {
            kind: NoiseKind::Glass,
            position: glass,
            loudness: 16.0,
        }));
        app.update();
        let engine = app.world().non_send::<AudioEngine>();
        assert!(engine.played.iter().any(|c| c.what == "glass"), "the glass was played");
        energy(&engine.capture().expect("memory output").render(24_000))
    }

    #[test]
    fn glass_on_the_right_of_where_vive_looks_is_louder_in_the_right_ear() {
        // Facing north, glass to the east is on the right.
        let (l, r) = hear_glass(std::f32::consts::FRAC_PI_2, Vec2::new(4.0, 0.0));
        assert!(r > 2.0 * l, "right {r} left {l}");
        // Turned to face south, the same glass is on the left.
        let (l, r) = hear_glass(-std::f32::consts::FRAC_PI_2, Vec2::new(4.0, 0.0));
        assert!(l > 2.0 * r, "right {r} left {l}");
    }

    #[test]
    fn a_thrown_item_is_heard_landing_when_it_is_drawn_landing_not_when_thrown() {
        let mut app = listener(0.0);
        app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(std::time::Duration::from_millis(100)));
        app.update();
        let landing = Vec2::new(9.0, 0.0);
        app.world_mut().write_message(Happened(GameEvent::Noise {
            kind: NoiseKind::Thud,
            position: landing,
            loudness: 8.0,
        }));
        // Read on the next frame, 100 ms on.
        let thrown = app.world().resource::<Time>().elapsed_secs_f64() + 0.1;
        let mut heard = None;
        for _ in 0..40 {
            app.update();
            let engine = app.world().non_send::<AudioEngine>();
            if heard.is_none() && engine.played.iter().any(|c| c.what == "thud") {
                heard = Some(app.world().resource::<Time>().elapsed_secs_f64() - thrown);
            }
        }
        let flight = crate::flight::flight_time_s(9.0) as f64;
        let heard = heard.expect("the thud was played");
        assert!(
            (heard - flight).abs() <= 0.1 + 1e-6,
            "heard {heard:.2} s after the throw, it lands after {flight:.2} s"
        );
    }

    #[test]
    fn far_glass_is_quieter_than_near_glass() {
        let near = hear_glass(0.0, Vec2::new(2.0, 0.0));
        let far = hear_glass(0.0, Vec2::new(12.0, 0.0));
        assert!(near.0 + near.1 > 3.0 * (far.0 + far.1), "near {near:?} far {far:?}");
    }
}
