//! Spatial sound for Vive (kira through `heist_audio`): the museum's cues (`heist_audio::museum`, the
//! same as Phantom's) placed around the listener at the predicted body, turned with the view; a thrown
//! item heard when it is drawn landing; the alarm ringing on while raised.

use bevy::prelude::*;
use glam::{Vec2, Vec3};
use heist_audio::museum::{self, MuseumCue, Sound};
use heist_audio::{AudioEngine, AudioSettings};
use heist_shared::protocol::{GuardView, Phase, ViveAvatar};
use heist_shared::rules;

use crate::client::{Happened, ViveState, ViveSystems};
use crate::flight;
use crate::intent::Intent;
use crate::space;

/// Seconds between repeats of the alarm while it is raised.
pub const ALARM_EVERY_S: f32 = 3.0;
/// Most thuds waiting for their thrown item to land (older ones are played at once).
const MAX_PENDING_THUDS: usize = 8;

/// Starts the engine and adds the sound systems.
pub fn add(app: &mut App, settings: &AudioSettings) -> Result<(), heist_audio::AudioError> {
    let engine = AudioEngine::new(settings)?;
    app.insert_non_send(engine)
        .init_resource::<Steps>()
        .init_resource::<Thuds>()
        .init_resource::<AlarmBell>()
        .add_systems(Update, (hear_events, land_thuds, hear_steps, ring_alarm).in_set(ViveSystems::Present));
    Ok(())
}

/// Every walker's last step.
#[derive(Resource, Default)]
struct Steps(museum::Steps);

/// Thuds of thrown items still in the air: (clock time it lands, its cue).
#[derive(Resource, Default)]
struct Thuds(Vec<(f64, MuseumCue)>);

/// Seconds since the alarm last rang.
#[derive(Resource, Default)]
struct AlarmBell(f32);

/// Where Vive hears a floor point at a height: his offset, from the predicted body and the view's facing.
fn ears(state: &ViveState, intent: &Intent) -> Option<impl Fn(&MuseumCue) -> Vec3> {
    let (me, facing) = (state.body()?, intent.facing);
    Some(move |cue: &MuseumCue| space::listener_offset(me, facing, space::EYE_HEIGHT_M, cue.at, cue.height_m))
}

/// The game's events as the museum's cues; a thud waits for its item to land.
fn hear_events(
    mut happened: MessageReader<Happened>,
    mut audio: NonSendMut<AudioEngine>,
    mut thuds: ResMut<Thuds>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    time: Res<Time>,
) {
    let (Some(me), Some(offset)) = (state.body(), ears(&state, &intent)) else { return };
    for cue in happened.read().filter_map(|Happened(e)| museum::event_cue(e)) {
        if cue.sound != Sound::Thud {
            audio.play_cue(&cue, offset(&cue));
            continue;
        }
        // The server lands a throw at once; it is drawn flying there, so it is heard landing then.
        if thuds.0.len() == MAX_PENDING_THUDS {
            let (_, early) = thuds.0.remove(0);
            audio.play_cue(&early, offset(&early));
        }
        let lands = time.elapsed_secs_f64() + flight::flight_time_s(cue.at.distance(me)) as f64;
        thuds.0.push((lands, cue));
    }
}

/// Plays the thuds whose items have landed.
fn land_thuds(
    mut audio: NonSendMut<AudioEngine>,
    mut thuds: ResMut<Thuds>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    time: Res<Time>,
) {
    let Some(offset) = ears(&state, &intent) else { return };
    let now = time.elapsed_secs_f64();
    while let Some(i) = thuds.0.iter().position(|(lands, _)| *lands <= now) {
        let (_, cue) = thuds.0.remove(i);
        audio.play_cue(&cue, offset(&cue));
    }
}

/// The guards' steps within their earshot (the rules' `GUARD_STEP_LOUDNESS`) and Vive's own.
fn hear_steps(
    mut audio: NonSendMut<AudioEngine>,
    mut steps: ResMut<Steps>,
    guards: Query<&GuardView>,
    avatar: Query<&ViveAvatar>,
    state: Res<ViveState>,
    intent: Res<Intent>,
) {
    let (Some(me), Some(offset)) = (state.body(), ears(&state, &intent)) else { return };
    let heard = |at: Vec2| at.distance(me) < rules::GUARD_STEP_LOUDNESS;
    for cue in guards.iter().filter_map(|g| steps.0.guard(g.id.0, g.position)).filter(|c| heard(c.at)) {
        audio.play_cue(&cue, offset(&cue));
    }
    if let Some(cue) = avatar.single().ok().and_then(|v| steps.0.vive(me, v.stance)) {
        audio.play_cue(&cue, offset(&cue));
    }
}

/// The alarm rings on from the workbench every few seconds while raised.
fn ring_alarm(
    mut audio: NonSendMut<AudioEngine>,
    mut bell: ResMut<AlarmBell>,
    state: Res<ViveState>,
    intent: Res<Intent>,
    time: Res<Time>,
) {
    if state.alarm == 0 || state.phase != Phase::Heist {
        return;
    }
    bell.0 += time.delta_secs();
    if let (true, Some(level), Some(offset)) = (bell.0 > ALARM_EVERY_S, state.level.as_ref(), ears(&state, &intent)) {
        bell.0 = 0.0;
        let cue = museum::alarm_cue(level.workbench);
        audio.play_cue(&cue, offset(&cue));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_audio::{AudioOutput, SpatialMode};
    use heist_shared::level::WallSet;
    use heist_shared::protocol::{GameEvent, NoiseKind};

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
