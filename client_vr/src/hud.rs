//! The HUD: time left, alarm level, targets, what is carried, and the latest messages — over the desktop
//! window, or in XR on a panel strapped to the off hand's wrist (the UI is drawn into an image that the
//! panel shows; look at your wrist to read it).

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use heist_shared::protocol::{ItemKind, ItemView, Phase, SessionView};

use crate::client::{ViveState, ViveSystems};

/// Messages shown at once.
pub const FEED_LINES: usize = 4;

#[derive(Component)]
struct Status;

#[derive(Component)]
struct Feed;

/// The wrist panel's picture, in pixels.
pub const WRIST_PX: (u32, u32) = (640, 320);

/// The image the wrist HUD is drawn into (XR mode).
#[derive(Resource, Clone)]
pub struct WristHud {
    /// The image.
    pub image: Handle<Image>,
}

/// The HUD.
pub struct HudPlugin {
    /// Draw into [`WristHud`] for a wrist panel instead of over the window.
    pub wrist: bool,
}

impl Plugin for HudPlugin {
    fn build(&self, app: &mut App) {
        if self.wrist {
            app.add_systems(Startup, spawn_wrist);
        } else {
            app.add_systems(Startup, spawn_window);
        }
        app.add_systems(Update, update.in_set(ViveSystems::Present));
    }
}

fn spawn_window(mut commands: Commands) {
    spawn(&mut commands, None);
}

fn spawn_wrist(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let image = Image::new_target_texture(WRIST_PX.0, WRIST_PX.1, TextureFormat::Rgba8UnormSrgb, None);
    let image = images.add(image);
    let camera = commands
        .spawn((
            Camera2d,
            Camera {
                order: -1,
                clear_color: ClearColorConfig::Custom(Color::srgba(0.02, 0.02, 0.05, 0.85)),
                ..default()
            },
            RenderTarget::Image(image.clone().into()),
        ))
        .id();
    commands.insert_resource(WristHud { image });
    spawn(&mut commands, Some(camera));
}

fn spawn(commands: &mut Commands, target: Option<Entity>) {
    let font = TextFont { font_size: FontSize::Px(if target.is_some() { 26.0 } else { 18.0 }), ..default() };
    let status = commands
        .spawn((
            Status,
            Text::new("Joining..."),
            font.clone(),
            TextColor(Color::WHITE),
            Node { position_type: PositionType::Absolute, top: Val::Px(8.0), left: Val::Px(10.0), ..default() },
        ))
        .id();
    let feed = commands
        .spawn((
            Feed,
            Text::new(""),
            font,
            TextColor(Color::srgb(1.0, 0.95, 0.7)),
            Node { position_type: PositionType::Absolute, bottom: Val::Px(8.0), left: Val::Px(10.0), ..default() },
        ))
        .id();
    if let Some(camera) = target {
        commands.entity(status).insert(UiTargetCamera(camera));
        commands.entity(feed).insert(UiTargetCamera(camera));
        return;
    }
    // The crosshair (desktop).
    commands.spawn((
        Text::new("+"),
        TextFont { font_size: FontSize::Px(22.0), ..default() },
        TextColor(Color::srgba(1.0, 1.0, 1.0, 0.7)),
        Node { position_type: PositionType::Absolute, top: Val::Percent(48.0), left: Val::Percent(49.5), ..default() },
    ));
}

/// The status line for the HUD.
pub fn status_text(state: &ViveState, session: Option<&SessionView>, items: &[&ItemView]) -> String {
    let Some(session) = session else { return "Joining...".into() };
    let phase = match session.phase {
        Phase::Lobby => match &state.hosted {
            Some(h) => format!("Lobby: press Enter (or the trigger) when ready\n{h}"),
            None => "Lobby: press Enter (or the trigger) when ready".to_owned(),
        },
        Phase::Heist => {
            let t = session.time_left_s.max(0.0) as u32;
            format!("{}:{:02} left", t / 60, t % 60)
        }
        Phase::Won => "WON".to_owned(),
        Phase::Lost(why) => format!("LOST ({why})"),
    };
    // The default font has ASCII and Latin-1 only.
    let alarm = format!("{}/{}", session.alarm, heist_shared::rules::ALARM_LOCKDOWN);
    let targets: Vec<String> =
        session.targets.iter().map(|(k, done)| format!("{k:?}{}", if *done { " (secured)" } else { "" })).collect();
    let carried: Vec<String> = state
        .carrying
        .iter()
        .map(|id| match items.iter().find(|i| i.id == *id).map(|i| &i.kind) {
            Some(ItemKind::Copy { artifact, .. }) => format!("{artifact:?} copy"),
            Some(ItemKind::Prop) => "prop".to_owned(),
            None => format!("item {}", id.0),
        })
        .collect();
    format!(
        "{phase}   alarm {alarm}\ntargets: {}\ncarrying: {}",
        targets.join(", "),
        if carried.is_empty() { "nothing".to_owned() } else { carried.join(", ") }
    )
}

fn update(
    state: Res<ViveState>,
    session: Query<&SessionView>,
    items: Query<&ItemView>,
    mut status: Query<&mut Text, (With<Status>, Without<Feed>)>,
    mut feed: Query<&mut Text, (With<Feed>, Without<Status>)>,
) {
    let items: Vec<&ItemView> = items.iter().collect();
    let text = status_text(&state, session.iter().next(), &items);
    if let Ok(mut s) = status.single_mut()
        && s.0 != text
    {
        s.0 = text;
    }
    let lines: Vec<&str> = state.feed.iter().rev().take(FEED_LINES).rev().map(|(_, l)| l.as_str()).collect();
    let text = lines.join("\n");
    if let Ok(mut f) = feed.single_mut()
        && f.0 != text
    {
        f.0 = text;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heist_shared::artifact::ArtifactKind;
    use heist_shared::protocol::{ItemId, ItemPlace};

    #[test]
    fn the_status_shows_time_alarm_targets_and_what_is_carried() {
        let state = ViveState { carrying: vec![ItemId(4)], ..Default::default() };
        let session = SessionView {
            phase: Phase::Heist,
            time_left_s: 125.0,
            alarm: 1,
            targets: vec![(ArtifactKind::Crown, true), (ArtifactKind::Idol, false)],
            present: (true, true),
            difficulty: Default::default(),
        };
        let look = heist_shared::artifact::look(ArtifactKind::Idol);
        let item = ItemView {
            id: ItemId(4),
            kind: ItemKind::Copy { artifact: ArtifactKind::Idol, look },
            place: ItemPlace::Carried,
        };
        let text = status_text(&state, Some(&session), &[&item]);
        assert!(text.contains("2:05 left"), "{text}");
        assert!(text.contains("alarm 1/3"), "{text}");
        assert!(text.contains("Crown (secured)") && text.contains("Idol"), "{text}");
        assert!(text.is_ascii(), "the default font draws it: {text}");
        assert!(text.contains("carrying: Idol copy"), "{text}");
    }
}
