//! What Phantom hears of the museum and of the copy: the museum's cues around the workbench
//! (`heist_audio::museum`, the same as Vive's) and the contact sound of the stylus on the copy.

use bevy::prelude::*;
use glam::Vec3;
use heist_client::Inbox;
use heist_shared::artifact::MaterialClass;
use heist_shared::protocol::{GameEvent, GuardView, ViveAvatar};

use crate::audio::synth::ContactParams;
use crate::audio::{AudioEngine, listener_offset, museum};
use crate::bench::Haptics;
use crate::schedule::HeistEvent;
use crate::state::Workbench;

/// The resources the sound systems keep (the client chains the systems in its `Sound` set, before
/// speech: a frame's sounds start with its words).
pub(crate) fn init(app: &mut App) {
    app.init_resource::<Steps>().init_resource::<Contact>();
}

/// Every walker's last step, for the museum's footsteps (a new round starts afresh).
#[derive(Resource, Default)]
pub(crate) struct Steps(museum::Steps);

/// The museum around Phantom's workbench (`heist_audio::museum`, the same cues Vive hears): noises,
/// guards' barks, radios and steps, Vive's steps, the alarm.
pub(crate) fn museum_sounds(
    mut events: MessageReader<HeistEvent>,
    mut steps: ResMut<Steps>,
    inbox: Res<Inbox>,
    guards: Query<&GuardView>,
    vive: Query<&ViveAvatar>,
    mut audio: NonSendMut<AudioEngine>,
) {
    let Some(bench) = inbox.level.as_ref().map(|l| l.workbench) else { return };
    let mut play = |cue: museum::MuseumCue| audio.play_cue(&cue, listener_offset(bench, cue.at, cue.height_m));
    for HeistEvent(e) in events.read() {
        if matches!(e, GameEvent::RoundStarted(_)) {
            steps.0 = museum::Steps::default();
        }
        museum::event_cue(e).into_iter().for_each(&mut play);
    }
    guards.iter().filter_map(|g| steps.0.guard(g.id.0, g.position)).for_each(&mut play);
    if let Some(cue) = vive.iter().next().and_then(|v| steps.0.vive(v.position, v.stance)) {
        play(cue);
    }
}

/// What the contact sound remembers between frames: whether the stylus touched, and its last sample
/// (time, position), for its sliding speed.
#[derive(Resource, Default)]
pub(crate) struct Contact {
    touching: bool,
    last_tool: Option<(u64, Vec3)>,
}

/// Drives the contact sound from this frame's haptic samples: force and sliding speed, taps on impact;
/// a new round starts afresh.
pub(crate) fn contact_sound(
    mut events: MessageReader<HeistEvent>,
    mut contact: ResMut<Contact>,
    workbench: Res<Workbench>,
    haptics: Haptics,
    mut audio: NonSendMut<AudioEngine>,
) {
    if events.read().any(|HeistEvent(e)| matches!(e, GameEvent::RoundStarted(_))) {
        *contact = Contact::default();
    }
    let params = contact_params(haptics.samples(), &mut contact.last_tool, workbench.feel);
    let touching = params.force_n > 0.05;
    if touching && !contact.touching {
        audio.tap((params.force_n / 2.0).min(1.0));
    }
    contact.touching = touching;
    audio.contact(params);
}

/// The contact sound's parameters from force samples (mean contact force and sliding speed of the
/// stylus); `last` carries the previous sample between frames; `feel` sets hardness and roughness,
/// and a ribbed copy's ridges tick at the rate the stylus crosses them (its speed up or down the copy
/// over their spacing).
pub fn contact_params(
    samples: &[haptic_rig::ForceSample],
    last: &mut Option<(u64, Vec3)>,
    feel: Option<MaterialClass>,
) -> ContactParams {
    let (mut force, mut speed, mut climb, mut n) = (0.0, 0.0, 0.0, 0u32);
    for s in samples {
        let f = s.contact_force.length();
        if let Some((t, p)) = *last
            && s.t_us > t
        {
            let v = (s.tool_position - p) / ((s.t_us - t) as f32 * 1e-6);
            let normal = s.contact_force.normalize_or_zero();
            let slip = v - normal * v.dot(normal);
            speed += slip.length();
            climb += slip.y.abs();
        }
        *last = Some((s.t_us, s.tool_position));
        force += f;
        n += 1;
    }
    if n == 0 {
        return ContactParams::default();
    }
    let feel = feel.unwrap_or(MaterialClass::HardSmooth);
    let ridges_per_s = feel.material().ridges.map_or(0.0, |r| climb / n as f32 / r.spacing_m);
    ContactParams {
        force_n: force / n as f32,
        slip_m_per_s: speed / n as f32,
        hardness: if feel.is_hard() { 1.0 } else { 0.2 },
        roughness: if feel.is_rough() { 1.0 } else { 0.1 },
        ridges_per_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audio::{AudioOutput, AudioSettings, SpatialMode};
    use haptic_rig::ForceSample;

    /// A second of 1 kHz samples of the stylus sliding along +x at `speed` m/s, pushed with `force` N.
    fn stroke(force: f32, speed: f32) -> Vec<ForceSample> {
        (0..1000u64)
            .map(|i| ForceSample {
                t_us: 1_000_000 + i * 1000,
                contact_force: Vec3::Y * force,
                tool_position: Vec3::X * speed * i as f32 * 1e-3,
                contacts: if force > 0.0 { 12 } else { 0 },
                ..Default::default()
            })
            .collect()
    }

    #[test]
    fn haptic_contact_drives_the_contact_sound_and_free_space_leaves_it_silent() {
        let mut audio = AudioEngine::new(&AudioSettings {
            output: AudioOutput::Manual,
            spatial: SpatialMode::Hrtf,
            ..Default::default()
        })
        .expect("audio starts");
        let capture = audio.capture().expect("memory output").clone();
        let energy = |frames: Vec<(f32, f32)>| frames.iter().map(|f| f.0 * f.0 + f.1 * f.1).sum::<f32>();
        let mut last = None;
        let free = contact_params(&stroke(0.0, 0.05), &mut last, Some(MaterialClass::HardRough));
        assert_eq!(free.force_n, 0.0);
        audio.contact(free);
        assert!(energy(capture.render(24_000)) < 1e-9, "free space is silent");
        let mut last = None;
        let sliding = contact_params(&stroke(1.2, 0.05), &mut last, Some(MaterialClass::HardRough));
        assert!((sliding.force_n - 1.2).abs() < 1e-4 && (sliding.slip_m_per_s - 0.05).abs() < 1e-3, "{sliding:?}");
        audio.contact(sliding);
        assert!(energy(capture.render(24_000)) > 1e-2, "the stylus sliding on a copy is heard");
    }

    #[test]
    fn stroking_up_a_ribbed_copy_ticks_once_per_ridge_crossed_and_a_smooth_one_never() {
        // Up the side of the copy (pressed along −x) at 6 cm/s: 20 ridges 3 mm apart a second.
        let up: Vec<ForceSample> = stroke(1.0, 0.06)
            .into_iter()
            .map(|s| ForceSample {
                contact_force: Vec3::X,
                tool_position: Vec3::new(0.04, s.tool_position.x, 0.0),
                ..s
            })
            .collect();
        let ribbed = contact_params(&up, &mut None, Some(MaterialClass::SoftRough));
        assert!((ribbed.ridges_per_s - 20.0).abs() < 0.1, "{ribbed:?}");
        assert_eq!(contact_params(&up, &mut None, Some(MaterialClass::SoftSmooth)).ridges_per_s, 0.0);
        // Round the copy, along the ridges: none crossed.
        assert!(contact_params(&stroke(1.0, 0.06), &mut None, Some(MaterialClass::SoftRough)).ridges_per_s < 1e-3);
    }
}
