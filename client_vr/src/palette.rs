//! The meshes and materials the museum is dressed with, made once and shared: every case, guard, copy
//! of a kind and shard uses the same handles (so the renderer batches them and nothing is created per
//! object at run time). A guard's alert shows by swapping his lamp's and meter's material for the
//! alert's, never by editing a material.
//!
//! You need this module to dress something new: take its handles from [`Palette`].

use bevy::prelude::*;
use heist_shared::artifact::ArtifactLook;
use heist_shared::protocol::GuardAlert;

use crate::textures::{self, SIZE};

/// Height of a case's pedestal top, metres.
pub const PEDESTAL_M: f32 = 1.0;
/// Width of a full awareness meter, metres.
pub const METER_WIDTH_M: f32 = 0.6;

/// Every alert state, in the order of [`Palette::alert`].
pub const ALERTS: [GuardAlert; 6] = [
    GuardAlert::Patrolling,
    GuardAlert::Suspicious,
    GuardAlert::Investigating,
    GuardAlert::Chasing,
    GuardAlert::Returning,
    GuardAlert::Searching,
];

/// A mesh with its material.
pub type Look = (Handle<Mesh>, Handle<StandardMaterial>);

/// The shared meshes and materials.
#[derive(Resource)]
pub struct Palette {
    /// Parquet for the floors (their meshes' UVs in metres, see [`textures::tile_uvs`]).
    pub parquet: Handle<StandardMaterial>,
    /// Painted plaster for the walls.
    pub plaster: Handle<StandardMaterial>,
    /// Dark wood: skirting boards, doors, the workbench.
    pub wood: Handle<StandardMaterial>,
    /// A unit cube (sized by its transform: skirting boards).
    pub unit_cube: Handle<Mesh>,
    /// A display case's pedestal.
    pub pedestal: Look,
    /// Its glass box (the shards use its material).
    pub glass: Look,
    /// A glass shard.
    pub shard: Handle<Mesh>,
    /// A guard's torso, in uniform (his legs and arms share the material).
    pub guard_body: Look,
    /// A guard's leg (hung from the hip joint).
    pub guard_leg: Handle<Mesh>,
    /// A guard's arm (hung from the shoulder joint).
    pub guard_arm: Handle<Mesh>,
    /// His head.
    pub guard_head: Look,
    /// His nose (shows where he looks).
    pub guard_nose: Handle<Mesh>,
    /// The alert lamp over his head.
    pub lamp: Handle<Mesh>,
    /// The awareness meter's bar.
    pub meter: Handle<Mesh>,
    /// A worthless prop.
    pub prop: Look,
    /// Phantom's steel tool.
    pub tool: Look,
    alerts: [Handle<StandardMaterial>; 6],
    looks: Vec<(ArtifactLook, Look)>,
}

impl FromWorld for Palette {
    fn from_world(world: &mut World) -> Self {
        let mut m = |mesh: Mesh| world.resource_mut::<Assets<Mesh>>().add(mesh);
        let (pedestal, glass, shard) = (
            m(Cuboid::new(0.6, PEDESTAL_M, 0.6).into()),
            m(Cuboid::new(0.5, 0.45, 0.5).into()),
            m(Cuboid::new(0.08, 0.005, 0.06).into()),
        );
        // Low-poly figures: eight sides round, as stealth games draw guards far off.
        let limb = |r: f32, l: f32| Capsule3d::new(r, l).mesh().longitudes(8).latitudes(4).build();
        let (leg, arm) = (m(limb(0.075, 0.7)), m(limb(0.055, 0.56)));
        let (body, head, nose, lamp, meter) = (
            m(limb(0.19, 0.4)),
            m(Sphere::new(0.13).mesh().uv(10, 6)),
            m(Cuboid::new(0.06, 0.06, 0.12).into()),
            m(Sphere::new(0.08).into()),
            m(Cuboid::new(METER_WIDTH_M, 0.06, 0.02).into()),
        );
        let (prop, tool) = (m(Cuboid::new(0.15, 0.15, 0.15).into()), m(Cylinder::new(0.006, 0.14).into()));
        let mut images = world.resource_mut::<Assets<Image>>();
        let (parquet, plaster, marble) = (
            images.add(textures::parquet(SIZE).image()),
            images.add(textures::plaster(SIZE).image()),
            images.add(textures::marble(SIZE).image()),
        );
        let unit_cube = world.resource_mut::<Assets<Mesh>>().add(Cuboid::new(1.0, 1.0, 1.0));
        let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
        let parquet = materials.add(StandardMaterial {
            base_color_texture: Some(parquet),
            perceptual_roughness: 0.45,
            reflectance: 0.4,
            ..default()
        });
        let plaster = materials.add(StandardMaterial {
            base_color_texture: Some(plaster),
            perceptual_roughness: 0.95,
            ..default()
        });
        let marble = materials.add(StandardMaterial {
            base_color_texture: Some(marble),
            perceptual_roughness: 0.25,
            ..default()
        });
        let mut plain = |c: Color| materials.add(StandardMaterial { base_color: c, ..default() });
        let (wood, uniform, skin) = (
            plain(Color::srgb(0.22, 0.12, 0.06)),
            plain(Color::srgb(0.1, 0.12, 0.3)),
            plain(Color::srgb(0.85, 0.7, 0.6)),
        );
        let glass_material = materials.add(StandardMaterial {
            base_color: Color::srgba(0.7, 0.9, 1.0, 0.25),
            alpha_mode: AlphaMode::Blend,
            perceptual_roughness: 0.05,
            ..default()
        });
        let prop_material =
            materials.add(StandardMaterial { base_color: Color::srgb(0.35, 0.35, 0.38), metallic: 0.3, ..default() });
        let steel =
            materials.add(StandardMaterial { base_color: Color::srgb(0.8, 0.8, 0.85), metallic: 0.9, ..default() });
        let alerts = ALERTS.map(|a| {
            let c = alert_colour(a);
            materials.add(StandardMaterial { base_color: c, emissive: c.to_linear() * 4.0, ..default() })
        });
        Self {
            parquet,
            plaster,
            wood,
            unit_cube,
            pedestal: (pedestal, marble),
            glass: (glass, glass_material),
            shard,
            guard_body: (body, uniform),
            guard_leg: leg,
            guard_arm: arm,
            guard_head: (head, skin),
            guard_nose: nose,
            lamp,
            meter,
            prop: (prop, prop_material),
            tool: (tool, steel),
            alerts,
            looks: Vec::new(),
        }
    }
}

impl Palette {
    /// The glowing material of an alert state (lamp and meter).
    pub fn alert(&self, alert: GuardAlert) -> Handle<StandardMaterial> {
        let i = ALERTS.iter().position(|a| *a == alert).unwrap_or(0);
        self.alerts[i].clone()
    }

    /// The mesh and material every copy with this look is drawn with (made on first use).
    pub fn look(
        &mut self,
        look: &ArtifactLook,
        meshes: &mut Assets<Mesh>,
        materials: &mut Assets<StandardMaterial>,
    ) -> Look {
        if let Some((_, handles)) = self.looks.iter().find(|(l, _)| l == look) {
            return handles.clone();
        }
        let [r, g, b] = look.colour_srgb;
        let material =
            materials.add(StandardMaterial { base_color: Color::srgb_u8(r, g, b), metallic: 0.3, ..default() });
        let handles = (meshes.add(look_mesh(look)), material);
        self.looks.push((look.clone(), handles.clone()));
        handles
    }
}

/// The mesh of an artifact's look: every copy of a kind gets the same one.
pub fn look_mesh(look: &ArtifactLook) -> Mesh {
    let [w, h, _] = look.size_m;
    match look.style_id {
        0 => Torus::new(w * 0.35, w * 0.5).into(),
        1 => Capsule3d::new(w * 0.5, (h - w).max(0.01)).into(),
        _ => Cuboid::new(w, h, w * 0.6).into(),
    }
}

/// The colour of a guard's alert lamp.
pub fn alert_colour(alert: GuardAlert) -> Color {
    match alert {
        GuardAlert::Patrolling => Color::srgb(0.2, 0.9, 0.3),
        GuardAlert::Suspicious => Color::srgb(1.0, 0.85, 0.1),
        GuardAlert::Investigating => Color::srgb(1.0, 0.5, 0.05),
        GuardAlert::Chasing => Color::srgb(1.0, 0.1, 0.1),
        GuardAlert::Returning => Color::srgb(0.3, 0.6, 1.0),
        GuardAlert::Searching => Color::srgb(1.0, 0.3, 0.6),
    }
}
