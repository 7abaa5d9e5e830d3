//! What a game puts on its own entities: the tool the device moves, the objects it touches, their
//! materials, and the volume collision is checked in.
//!
//! You need this module to make an entity touchable. Every component is `Reflect`ed and registered, so
//! it can come from a scene file or be added to a glTF node. The paper's names: [`HapticTool`] is the
//! virtual tool the EventHandler attaches to the device; [`HapticCollider`] the ColletteStaticMeshActor;
//! [`ForceComponent`] the ForceComponent; [`CollisionVolume`] the ColletteVolume.

use bevy::prelude::*;

use crate::tree::SphereTree;

/// The virtual tool: its `Transform` follows the device every frame (in `PreUpdate`), through the
/// virtual coupling with 6-DOF rendering or on the surface with the 3-DOF proxy. Its material is the
/// [`ForceComponent`] beside it (default: far stiffer than anything it touches).
///
/// One tool per app: the device's. Its tree is in the tool's frame, metres; without one (or until it is
/// loaded) the tool is a ball of `tip_radius_m`.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
#[require(Transform)]
pub struct HapticTool {
    /// The tool's sphere tree (`None`: a ball).
    pub tree: Option<Handle<SphereTree>>,
    /// Radius of the ball used without a tree, m (default 0.003).
    pub tip_radius_m: f32,
}

impl Default for HapticTool {
    fn default() -> Self {
        Self { tree: None, tip_radius_m: 0.003 }
    }
}

impl HapticTool {
    /// A tool shaped by `tree`.
    pub fn new(tree: Handle<SphereTree>) -> Self {
        Self { tree: Some(tree), ..Self::default() }
    }

    /// A ball tip of `radius_m`.
    pub fn ball(radius_m: f32) -> Self {
        Self { tree: None, tip_radius_m: radius_m }
    }
}

/// A collidable object the tool can touch (the paper's ColletteStaticMeshActor): its sphere tree, in
/// the entity's frame (metres; a `Transform` scale is not applied — bake it into the tree). Its
/// `GlobalTransform` is read every frame: an entity the game moves (parented or not) moves on the
/// collision thread. Its material is the [`ForceComponent`] beside it (default
/// [`ForceComponent::default`]).
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
#[require(Transform)]
pub struct HapticCollider {
    /// The object's sphere tree.
    pub tree: Handle<SphereTree>,
}

impl HapticCollider {
    /// A collider shaped by `tree`.
    pub fn new(tree: Handle<SphereTree>) -> Self {
        Self { tree }
    }
}

/// Makes a [`HapticCollider`] an object the tool can push: a rigid body of `mass_kg` that your game
/// simulates. The haptic thread moves it at once as the tool pushes (so the hand feels its mass, not a
/// wall), and every frame hands back what the tool did to it as a [`ToolPushed`](crate::ToolPushed)
/// (impulses to apply to your body; with the `avian3d` feature, applied to its avian3d `RigidBody` for
/// you). Move the entity as your physics moves it: its poses reach the threads with their times, and
/// the haptic thread's copy follows them through a spring tuned to your game's latency
/// ([`ForceCompPlugin::pushes`](crate::ForceCompPlugin::pushes); `haptic_rig::push` explains why).
/// Give it the mass your rigid body has; its inertia is that of the tree at uniform density.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
#[require(HapticCollider)]
pub struct HapticPushable {
    /// The body's mass, kg (default 0.2).
    pub mass_kg: f32,
}

impl Default for HapticPushable {
    fn default() -> Self {
        Self { mass_kg: 0.2 }
    }
}

impl HapticPushable {
    /// A pushable body of `mass_kg`.
    pub fn new(mass_kg: f32) -> Self {
        Self { mass_kg }
    }
}

/// Ridges across a surface, felt as the tool slides over them.
#[derive(Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Default)]
#[type_path = "bevy_haptics"]
pub struct Ridges {
    /// Distance between ridges, m.
    pub spacing_m: f32,
    /// Height of a ridge, m.
    pub depth_m: f32,
    /// Stiffness their height is read with, N/m.
    pub stiffness_n_per_m: f32,
}

impl Default for Ridges {
    fn default() -> Self {
        Self { spacing_m: 0.003, depth_m: 0.0003, stiffness_n_per_m: 500.0 }
    }
}

/// How an object (or the tool) pushes back (the paper's ForceComponent): the volumetric penalty of its
/// overlap with the tool (paper Eq. 1), scaled. Two touching bodies' components combine (stiffness and
/// damping in series, friction as the geometric mean).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
pub struct ForceComponent {
    /// Force per overlap volume, N/m³ (default 3e6: 1 N at 0.33 cm³).
    pub stiffness_n_per_m3: f32,
    /// Damping on the relative normal velocity, N·s/m (default 2).
    pub damping_ns_per_m: f32,
    /// Coulomb friction coefficient (default 0.3).
    pub friction: f32,
    /// Ridges on the surface, repeating along the object's +Y (default none: smooth).
    pub ridges: Option<Ridges>,
    /// The paper's scaling factor: stiffness and damping are multiplied by it (default 1).
    pub force_scale: f32,
}

impl Default for ForceComponent {
    fn default() -> Self {
        let m = forcecomp::Material::default();
        Self {
            stiffness_n_per_m3: m.stiffness_n_per_m3,
            damping_ns_per_m: m.damping_ns_per_m,
            friction: m.friction,
            ridges: None,
            force_scale: 1.0,
        }
    }
}

impl ForceComponent {
    /// What forcecomp renders with.
    pub fn material(&self) -> forcecomp::Material {
        let scale = self.force_scale.max(0.0);
        forcecomp::Material {
            stiffness_n_per_m3: self.stiffness_n_per_m3.max(0.0) * scale,
            damping_ns_per_m: self.damping_ns_per_m.max(0.0) * scale,
            friction: self.friction.max(0.0),
            texture: self.ridges.map(|r| forcecomp::Texture::ribs(r.spacing_m, r.depth_m, r.stiffness_n_per_m)),
        }
    }

    /// The tool's default: far stiffer than anything it touches (so the object's material decides), with
    /// friction 1 (so the object's coefficient decides).
    pub fn rigid_tool() -> Self {
        Self { stiffness_n_per_m3: 1e12, damping_ns_per_m: 1e6, friction: 1.0, ridges: None, force_scale: 1.0 }
    }
}

/// Restricts collision checks to a box (the paper's ColletteVolume): objects whose bounds do not touch
/// it give no contact. The box is the entity's `GlobalTransform` translation ± `half_extents_m`
/// (axis-aligned in the world). Without one, collisions are checked everywhere. One per app.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[type_path = "bevy_haptics"]
#[require(Transform)]
pub struct CollisionVolume {
    /// Half the box's size along each world axis, m.
    pub half_extents_m: Vec3,
}

impl Default for CollisionVolume {
    fn default() -> Self {
        Self { half_extents_m: Vec3::splat(0.5) }
    }
}

/// Watches two colliders against each other (the paper's AddCollisionWatcher between two actors): the
/// collision thread measures their overlap every step, and [`PairContactStarted`](crate::PairContactStarted)
/// / [`PairContactEnded`](crate::PairContactEnded) are triggered on this entity (and sent as messages).
/// Objects do not push each other: this tells the game they touch. Put it on an entity of its own;
/// it starts once both have reached the collision thread. One watcher per pair; at most
/// `haptic_rig::MAX_PAIR_WATCHERS` at once.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component)]
#[type_path = "bevy_haptics"]
pub struct CollisionWatcher {
    /// One collider.
    #[entities]
    pub a: Entity,
    /// The other.
    #[entities]
    pub b: Entity,
}

impl CollisionWatcher {
    /// Watches colliders `a` and `b` against each other.
    pub fn new(a: Entity, b: Entity) -> Self {
        Self { a, b }
    }
}
