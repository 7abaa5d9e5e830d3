//! The force stage bound to the haptic thread's ForceOnHapticTick: each watched object's contacts from
//! collette's pipeline → volumetric penalty → virtual coupling (or the spheres near the tip → 3-DOF
//! god-object) → safety layer → device, then the tool pose goes back to the pipeline.
//!
//! You need this module to see what the haptic thread does each tick (the rig binds it for you).
//! Everything it touches per tick is preallocated: the watchers' triple buffers, the objects' slots and
//! the sphere buffer, the rings of changes, the force-sample ring, the coupling and safety state.

use collette::pipeline::{MAX_TOUCHED, NearReader, PoseTrack, PoseWriter, SceneReader};
use forcecomp::{
    Ball, BodyMotion, GodObject, Material, ProxyConfig, SafetyLayer, SafetyPhase, SafetyStats, VirtualCoupling,
    volumetric_penalty_of,
};
use std::sync::Arc;

use collette::SignedDistanceGrid;
use glam::Vec3;
use haptic_common::{DeviceState, ForceOnHapticTick, ForceTorque, Pose};

use crate::WorkspaceMap;
use crate::push::{ObjectPush, PushCoupling, PushedBody};

/// One tick's forces, recorded for plots (preallocated ring; lost when full).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceSample {
    /// Device timestamp, µs.
    pub t_us: u64,
    /// Force sent to the device, N.
    pub force: Vec3,
    /// Torque sent to the device, N·m.
    pub torque: Vec3,
    /// Contact force on the simulated tool before coupling and safety (device frame), N.
    pub contact_force: Vec3,
    /// Where the simulated tool was (scene frame), m; with proxy rendering the tip (the device point,
    /// which sinks in; the proxy on the surface is the telemetry's `tool_pose`).
    pub tool_position: Vec3,
    /// Contacts used.
    pub contacts: u32,
    /// Age of the contact data, µs.
    pub data_age_us: u32,
    /// Sequence number of the collision step whose contacts were used.
    pub collision_sequence: u64,
}

/// What the tool felt of one object it touched on the last tick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjectContact {
    /// The object's id (as given in its [`ObjectSpec`](crate::ObjectSpec)).
    pub id: u32,
    /// Whether the tool touches it: their trees overlap (volumetric), or the proxy rests on it (3-DOF).
    pub touching: bool,
    /// Overlapping sphere pairs (volumetric) or its spheres near the tip (3-DOF proxy).
    pub contacts: u32,
    /// Overlap volume of the tool and the object, scene units³ (0 with the 3-DOF proxy).
    pub volume: f32,
    /// Force the object puts on the tool, scene frame, N (before coupling and safety; 0 with
    /// [`Rendering::Off`]).
    pub force: Vec3,
    /// Torque the object puts on the tool about the tool's centre of mass, scene frame, N·m.
    pub torque: Vec3,
}

/// Latest state of the force stage, for the game thread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigTelemetry {
    /// The device sample of the last tick.
    pub device: DeviceState,
    /// The simulated tool in the scene.
    pub tool_pose: Pose,
    /// Force and torque sent to the device on the last tick.
    pub output: ForceTorque,
    /// Contacts (or spheres near the tip) used.
    pub contacts: u32,
    /// Newest collision step whose results were used (0: none yet, or nothing watched).
    pub collision_sequence: u64,
    /// Age of the oldest tool pose those results rest on, µs (for a watcher that has published nothing
    /// yet, the time since its object was added; 0 with nothing watched).
    pub data_age_us: u64,
    /// Safety phase.
    pub safety_phase: SafetyPhase,
    /// Safety gain (engagement × watchdog).
    pub safety_gain: f32,
    /// The grip was read outside the workspace, so forces are off (see [`forcecomp::Workspace`]).
    pub outside_workspace: bool,
    /// Safety counters.
    pub safety: SafetyStats,
    /// The contact of each object the tool touched (volumetric) or had spheres near its tip (3-DOF
    /// proxy), the first [`RigTelemetry::object_count`] in use (see [`RigTelemetry::objects`]).
    pub object_contacts: [ObjectContact; MAX_TOUCHED],
    /// How many of `object_contacts` are in use.
    pub object_count: u32,
}

impl RigTelemetry {
    /// The objects the tool touched (volumetric) or had spheres near its tip (3-DOF proxy) on the last
    /// tick, at most [`MAX_TOUCHED`]; the objects it is far from are not listed.
    pub fn objects(&self) -> &[ObjectContact] {
        &self.object_contacts[..(self.object_count as usize).min(MAX_TOUCHED)]
    }
}

impl Default for RigTelemetry {
    fn default() -> Self {
        Self {
            device: DeviceState::default(),
            tool_pose: Pose::IDENTITY,
            output: ForceTorque::ZERO,
            contacts: 0,
            collision_sequence: 0,
            data_age_us: 0,
            safety_phase: SafetyPhase::WaitingForSmallForce,
            safety_gain: 0.0,
            outside_workspace: false,
            safety: SafetyStats::default(),
            object_contacts: [ObjectContact::default(); MAX_TOUCHED],
            object_count: 0,
        }
    }
}

/// Whether the device feels the contact force through a virtual coupling or directly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rendering {
    /// Virtual coupling (6-DOF, stable for stiff contacts).
    Coupled,
    /// The contact force straight to the device (for comparison; unstable when stiff).
    Direct,
    /// 3-DOF god-object: the tool is its tip (the device point), held outside the objects' inner
    /// spheres by a proxy on their surface; force only, no torque (`forcecomp::proxy`).
    Proxy,
    /// No contact force: contacts are detected and reported (telemetry, [`ObjectContact`]) and the tool
    /// is the device itself, but only your own `ForceOnHapticTick` delegates push the device (the safety
    /// layer still covers them). The paper's set-up without ForceComp.
    Off,
}

/// How the 3-DOF proxy feels a material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyRendering {
    /// The proxy's spring is the tool-and-object material's volumetric stiffness times this, m²
    /// (default 1e-5: 3e6 N/m³ feels like 30 N/m), capped at the device's stiffness limit. Set it to
    /// the tool's overlap volume per depth at a flat face, and a copy feels as stiff as with the
    /// volumetric rendering at that depth.
    pub volume_per_depth_m2: f32,
    /// Damping of the tip's speed into the surface, N·s/m (default 0.5).
    pub damping_ns_per_m: f32,
    /// Spheres are handed to the proxy this far beyond its distance from the tip and its radius, scene
    /// units (default 0.003: the tip moves less than that between collision steps below 3 m/s).
    pub margin: f32,
    /// Radius of the tip, scene units (default 0.004): a few times the radius of an Inner Sphere
    /// Tree's spheres near the surface (1–3 mm for a 10 cm object of a few thousand spheres), so that
    /// the surface it feels is smooth (`forcecomp::proxy`).
    pub tip_radius: f32,
}

impl Default for ProxyRendering {
    fn default() -> Self {
        Self { volume_per_depth_m2: 1e-5, damping_ns_per_m: 0.5, margin: 0.003, tip_radius: 0.004 }
    }
}

/// A watched object as the haptic thread sees it: its slot in the collision pipeline, its material and
/// motion.
pub(crate) struct WatchedObject {
    pub(crate) id: u32,
    /// Its object slot in the collision pipeline (how the tool's scene watcher names it).
    pub(crate) slot: u32,
    pub(crate) material: Material,
    /// Where the game placed it, at rest (while it has no track).
    pub(crate) motion: BodyMotion,
    /// Its centre of mass in its own frame.
    pub(crate) center_of_mass: Vec3,
    /// Its last poses while the game moves it (see [`WatchedObject::motion_at`]).
    pub(crate) track: Option<PoseTrack>,
    /// The haptic body of an object the tool pushes (see [`crate::push`]).
    pub(crate) pushed: Option<PushedBody>,
    /// Its surface grid: the 3-DOF proxy is held on it instead of on its spheres.
    pub(crate) surface: Option<Arc<SignedDistanceGrid>>,
}

impl WatchedObject {
    /// Its centre of mass, orientation and velocities at `now_us`: read from its track while the game
    /// moves it (so the damping and friction see the contact point's velocity), else where it was placed.
    fn motion_at(&self, now_us: u64) -> BodyMotion {
        let Some(motion) = self.track.and_then(|t| t.at(now_us)) else { return self.motion };
        let center_of_mass = motion.pose.transform_point(self.center_of_mass);
        BodyMotion {
            center_of_mass,
            orientation: motion.pose.rotation,
            linear_velocity: motion.velocity_at(center_of_mass),
            angular_velocity: motion.angular_velocity,
        }
    }

    /// What the tool touches at `now_us`: the haptic body of a pushed object, else the game's.
    fn touched_motion(&self, now_us: u64) -> BodyMotion {
        match &self.pushed {
            Some(body) => body.motion(),
            None => self.motion_at(now_us),
        }
    }

    /// Its pose (scene frame) for a motion of its centre of mass.
    fn pose_of(&self, motion: &BodyMotion) -> Pose {
        crate::push::pose_of(motion, self.center_of_mass)
    }
}

/// What the threads hand back to the game thread to free (held only to be dropped there).
#[expect(dead_code, reason = "the values are only dropped, on the game thread")]
pub(crate) enum Returned {
    Object(Box<WatchedObject>),
    Surface(Arc<SignedDistanceGrid>),
}

/// An object's surface grid at its pose (scene frame), as the 3-DOF proxy feels it: the tip's overlap
/// with a flat face at the signed distance the grid gives (`forcecomp::half_space_overlap`).
#[derive(Clone, Copy)]
pub struct GridAt<'a> {
    /// The grid, in the object's frame.
    pub grid: &'a SignedDistanceGrid,
    /// The object's pose.
    pub pose: Pose,
}

impl GridAt<'_> {
    /// How deep `p` (scene frame) is inside the object, and the unit normal into it (scene frame).
    pub fn depth(&self, p: Vec3) -> (f32, Vec3) {
        let local = self.pose.rotation.inverse() * (p - self.pose.translation);
        let (depth, inward) = self.grid.distance_and_gradient(local);
        (depth, self.pose.rotation * inward.normalize_or_zero())
    }
}

impl forcecomp::TipField for GridAt<'_> {
    fn overlap_and_gradient(&self, p: Vec3, tip_radius: f32) -> (f32, Vec3) {
        let (depth, inward) = self.depth(p);
        forcecomp::half_space_overlap(tip_radius, depth, inward)
    }
}

/// The surface grids of the objects near the proxy's tip, each at its pose: their overlaps add up.
struct GridSurfaces<'a> {
    objects: &'a [Option<Box<WatchedObject>>],
    near: &'a [(u32, Pose)],
}

impl GridSurfaces<'_> {
    /// Each grid near the tip with its object's slot.
    fn grids(&self) -> impl Iterator<Item = (u32, GridAt<'_>)> + '_ {
        self.near.iter().filter_map(move |&(slot, pose)| {
            let grid = self.objects.get(slot as usize)?.as_ref()?.surface.as_deref()?;
            Some((slot, GridAt { grid, pose }))
        })
    }
}

impl forcecomp::TipField for GridSurfaces<'_> {
    fn overlap_and_gradient(&self, p: Vec3, tip_radius: f32) -> (f32, Vec3) {
        self.grids().fold((0.0, Vec3::ZERO), |(v, g), (_, grid)| {
            let (dv, dg) = grid.overlap_and_gradient(p, tip_radius);
            (v + dv, g + dg)
        })
    }
}

/// The reader of the tool's scene watcher: overlaps with every object (volumetric) or every object's
/// spheres near the tip (proxy).
pub(crate) enum SceneInput {
    Contacts(SceneReader),
    Near(NearReader),
}

/// Changes the game thread sends the force stage (boxed there; the replaced boxes come back).
pub(crate) enum ForceCommand {
    /// Watches an object in its slot.
    Add(Box<WatchedObject>),
    /// Stops watching the object in a slot.
    Remove(u32),
    SetTool {
        center_of_mass: Vec3,
        material: Material,
    },
    /// An object the game placed: its new centre of mass and orientation (scene frame), at rest.
    Move {
        slot: u32,
        center_of_mass: Vec3,
        orientation: glam::Quat,
    },
    /// An object the game moves: its track, read every tick.
    Track {
        slot: u32,
        track: PoseTrack,
    },
    /// An object's surface grid (or none again).
    Surface {
        slot: u32,
        grid: Option<Arc<SignedDistanceGrid>>,
    },
}

/// The force stage's state (lives on the haptic thread).
pub struct ForceStage {
    pub(crate) map: WorkspaceMap,
    pub(crate) rendering: Rendering,
    pub(crate) coupling: VirtualCoupling,
    pub(crate) safety: SafetyLayer,
    pub(crate) god: GodObject,
    pub(crate) proxy: ProxyRendering,
    /// The device's stiffness limit, N/m (the proxy's spring never exceeds it).
    pub(crate) max_stiffness_n_per_m: f32,
    /// Writes the tool's pose (and the proxy's reach) to the collision thread.
    pub(crate) tool: PoseWriter,
    pub(crate) tool_center_of_mass: Vec3,
    pub(crate) tool_material: Material,
    /// The tool against every object.
    pub(crate) scene: SceneInput,
    /// The watched objects by their slot in the collision pipeline. Boxed so that objects move in and
    /// out through the rings whole: unboxing here would free the box on this thread.
    pub(crate) objects: Vec<Option<Box<WatchedObject>>>,
    /// How many objects are watched, and since when (device time) there has been one.
    pub(crate) watched: usize,
    pub(crate) watched_since_us: u64,
    pub(crate) commands: rtrb::Consumer<ForceCommand>,
    pub(crate) garbage: rtrb::Producer<Returned>,
    /// Proxy rendering: every object's spheres near the tip this tick, with the object's slot.
    pub(crate) balls: Vec<Ball>,
    pub(crate) ball_objects: Vec<u32>,
    /// Proxy rendering: the objects near the tip that have a surface grid (slot, pose).
    pub(crate) grids_near: Vec<(u32, Pose)>,
    pub(crate) telemetry: triple_buffer::Input<RigTelemetry>,
    pub(crate) samples: rtrb::Producer<ForceSample>,
    /// This tick's contact with each object touched, the first `touched` in use.
    pub(crate) object_contacts: [ObjectContact; MAX_TOUCHED],
    pub(crate) touched: usize,
    /// How pushed objects follow the game's bodies, and where their pushes go.
    pub(crate) push_coupling: PushCoupling,
    pub(crate) pushes: rtrb::Producer<ObjectPush>,
}

impl ForceStage {
    /// One tick: adds the safe contact force to whatever earlier delegates added, then replaces the
    /// tick's total with the safety layer's output. Allocation-free.
    pub fn on_tick(&mut self, tick: &ForceOnHapticTick) {
        self.apply_commands(tick.device.timestamp_us);
        if self.rendering == Rendering::Proxy {
            return self.on_proxy_tick(tick);
        }
        let device = tick.device;

        // The tool as the force law sees it: the simulated tool (or the device itself when direct).
        let tool_device = match self.rendering {
            Rendering::Coupled => self.coupling.tool_pose(),
            Rendering::Direct | Rendering::Proxy | Rendering::Off => device.pose,
        };
        let (v, w) = match self.rendering {
            Rendering::Coupled => (self.coupling.tool_velocity(), self.coupling.tool_angular_velocity()),
            Rendering::Direct | Rendering::Proxy | Rendering::Off => (device.linear_velocity, device.angular_velocity),
        };
        let tool_scene = self.map.to_scene(&tool_device);
        let com = tool_scene.transform_point(self.tool_center_of_mass);
        let tool_motion = BodyMotion {
            center_of_mass: com,
            orientation: tool_scene.rotation,
            linear_velocity: self.map.velocity_to_scene(v),
            angular_velocity: self.map.angular_velocity_to_scene(w),
        };
        let mut contact = ForceTorque::ZERO;
        self.touched = 0;
        let SceneInput::Contacts(reader) = &mut self.scene else { return };
        let set = reader.latest();
        let (watched, since_us, contacts) = (self.watched, self.watched_since_us, set.contacts().len());
        let used = Published { sequence: set.sequence, timestamp_us: set.timestamp_us, contacts, watched, since_us }
            .at(device.timestamp_us);
        for touched in set.touched() {
            let Some(object) = self.objects.get_mut(touched.object as usize).and_then(Option::as_mut) else { continue };
            let contacts = set.contacts_of(touched);
            let ft = if self.rendering == Rendering::Off {
                ForceTorque::ZERO
            } else {
                let material = self.tool_material.combine(&object.material);
                let motion = object.touched_motion(device.timestamp_us);
                let ft = volumetric_penalty_of(contacts, touched.total_volume, &tool_motion, &motion, &material);
                if let Some(body) = &mut object.pushed {
                    // Equal and opposite; the torque moved from the tool's centre of mass to the object's.
                    let lever = com - motion.center_of_mass;
                    body.add_reaction(-ft.force, -ft.torque - lever.cross(ft.force));
                }
                ft
            };
            contact.force += ft.force;
            contact.torque += ft.torque;
            if let Some(slot) = self.object_contacts.get_mut(self.touched) {
                *slot = ObjectContact {
                    id: object.id,
                    touching: !contacts.is_empty(),
                    contacts: contacts.len() as u32,
                    volume: touched.total_volume,
                    force: ft.force,
                    torque: ft.torque,
                };
                self.touched += 1;
            }
        }
        // Torque about the tool frame's origin (where the coupling acts) instead of the centre of mass.
        contact.torque += (com - tool_scene.translation).cross(contact.force);
        let contact_device = self.map.wrench_to_device(contact);

        let dt = tick.dt_s;
        let wanted = match self.rendering {
            Rendering::Coupled => self.coupling.step(&device, contact_device, dt),
            Rendering::Direct | Rendering::Proxy | Rendering::Off => contact_device,
        };
        let before = tick.total();
        let requested = ForceTorque { force: before.force + wanted.force, torque: before.torque + wanted.torque };
        let out = self.safety.apply_at(requested, dt, used.age_s(), device.pose.translation);
        tick.set(out);

        let tool_now = match self.rendering {
            Rendering::Coupled => self.map.to_scene(&self.coupling.tool_pose()),
            Rendering::Direct | Rendering::Proxy | Rendering::Off => self.map.to_scene(&device.pose),
        };
        self.tool.set(tool_now, device.timestamp_us);
        self.step_pushed(device.timestamp_us, dt);
        self.report(device, out, contact_device.force, tool_now.translation, tool_now, used);
    }

    /// Moves every pushed object's haptic body one tick and hands its impulses to the game.
    fn step_pushed(&mut self, now_us: u64, dt_s: f32) {
        let coupling = self.push_coupling;
        for object in self.objects.iter_mut().flatten().filter(|o| o.pushed.is_some()) {
            let game = object.motion_at(now_us);
            let Some(body) = &mut object.pushed else { continue };
            body.step(game, &coupling, dt_s, now_us);
            body.hand_over(|push| self.pushes.push(push).is_ok());
        }
    }

    /// Applies the game thread's changes at device time `now_us`; what they replace goes back to be
    /// freed there.
    fn apply_commands(&mut self, now_us: u64) {
        while let Ok(command) = self.commands.pop() {
            match command {
                ForceCommand::Add(object) => match self.objects.get_mut(object.slot as usize) {
                    Some(place) => {
                        if self.watched == 0 {
                            self.watched_since_us = now_us;
                        }
                        match place.replace(object) {
                            Some(old) => self.discard(old),
                            None => self.watched += 1,
                        }
                    }
                    None => self.discard(object),
                },
                ForceCommand::Remove(slot) => {
                    if let Some(old) = self.objects.get_mut(slot as usize).and_then(Option::take) {
                        self.watched -= 1;
                        self.discard(old);
                    }
                }
                ForceCommand::SetTool { center_of_mass, material } => {
                    self.tool_center_of_mass = center_of_mass;
                    self.tool_material = material;
                }
                ForceCommand::Move { slot, center_of_mass, orientation } => {
                    if let Some(o) = self.objects.get_mut(slot as usize).and_then(Option::as_mut) {
                        o.motion = BodyMotion { orientation, ..BodyMotion::at_rest(center_of_mass) };
                        o.track = None;
                        if let Some(body) = &mut o.pushed {
                            body.place(o.motion);
                        }
                    }
                }
                ForceCommand::Track { slot, track } => {
                    if let Some(o) = self.objects.get_mut(slot as usize).and_then(Option::as_mut) {
                        o.track = Some(track);
                    }
                }
                ForceCommand::Surface { slot, grid } => {
                    let old = match self.objects.get_mut(slot as usize).and_then(Option::as_mut) {
                        Some(o) => std::mem::replace(&mut o.surface, grid),
                        None => grid,
                    };
                    if let Some(old) = old {
                        self.give_back(Returned::Surface(old));
                    }
                }
            }
        }
    }

    fn discard(&mut self, object: Box<WatchedObject>) {
        self.give_back(Returned::Object(object));
    }

    fn give_back(&mut self, item: Returned) {
        if let Err(rtrb::PushError::Full(item)) = self.garbage.push(item) {
            std::mem::forget(item); // leak rather than free on this thread (the ring is sized not to fill)
        }
    }

    /// One tick of 3-DOF proxy rendering: the tip against the spheres near it, no coupling, no torque.
    fn on_proxy_tick(&mut self, tick: &ForceOnHapticTick) {
        let device = tick.device;
        let tip = self.map.to_scene(&device.pose);
        self.balls.clear();
        self.ball_objects.clear();
        self.grids_near.clear();
        self.touched = 0;
        let SceneInput::Near(reader) = &mut self.scene else { return };
        let set = reader.latest();
        let (watched, since_us, contacts) = (self.watched, self.watched_since_us, set.len());
        let used = Published { sequence: set.sequence, timestamp_us: set.timestamp_us, contacts, watched, since_us }
            .at(device.timestamp_us);
        for s in set.as_slice().iter().take(self.balls.capacity()) {
            let Some(object) = self.objects.get(s.object as usize).and_then(Option::as_ref) else { continue };
            if object.surface.is_none() {
                self.balls.push(Ball { center: s.center, radius: s.radius });
                self.ball_objects.push(s.object);
            } else if !self.grids_near.iter().any(|g| g.0 == s.object) && self.grids_near.len() < MAX_TOUCHED {
                // Held on its surface grid instead of its spheres.
                let pose = object.pose_of(&object.touched_motion(device.timestamp_us));
                self.grids_near.push((s.object, pose));
            }
            // Each object near the tip once, with its count of spheres.
            let listed = &mut self.object_contacts[..self.touched];
            match listed.iter_mut().find(|c| c.id == object.id) {
                Some(c) => c.contacts += 1,
                None if self.touched < MAX_TOUCHED => {
                    self.object_contacts[self.touched] =
                        ObjectContact { id: object.id, contacts: 1, ..Default::default() };
                    self.touched += 1;
                }
                None => {}
            }
        }
        let balls = self.balls.as_slice();
        let grids = GridSurfaces { objects: &self.objects, near: &self.grids_near };
        // The spring of the material the proxy rests on: the object of the sphere (or the surface grid)
        // nearest to it.
        let near = if self.god.in_contact() { self.god.proxy() } else { tip.translation };
        let nearest_ball = balls
            .iter()
            .enumerate()
            .map(|(i, b)| (b.center.distance(near) - b.radius, self.ball_objects[i]))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let nearest_grid =
            grids.grids().map(|(slot, grid)| (-grid.depth(near).0, slot)).min_by(|a, b| a.0.total_cmp(&b.0));
        let nearest_slot = match (nearest_ball, nearest_grid) {
            (Some(b), Some(g)) => Some(if g.0 <= b.0 { g.1 } else { b.1 }),
            (b, g) => b.or(g).map(|n| n.1),
        }
        .map(|slot| slot as usize);
        let nearest = nearest_slot.and_then(|slot| self.objects.get(slot)).and_then(Option::as_deref);
        let material = nearest.map(|o| self.tool_material.combine(&o.material));
        let config = ProxyConfig {
            stiffness_n_per_m: material
                .map_or(0.0, |m| m.stiffness_n_per_m3 * self.proxy.volume_per_depth_m2)
                .min(self.max_stiffness_n_per_m)
                .max(f32::MIN_POSITIVE),
            damping_ns_per_m: self.proxy.damping_ns_per_m,
            friction: material.map_or(0.0, |m| m.friction),
            tip_radius: self.proxy.tip_radius,
        };
        let scale = self.map.scale.max(f32::MIN_POSITIVE);
        // The tip's speed against the surface it is near (a moving object's surface moves too).
        let body = nearest.map(|o| o.touched_motion(device.timestamp_us));
        let surface = body.map_or(Vec3::ZERO, |b| b.velocity_at(near));
        let velocity = (self.map.velocity_to_scene(device.linear_velocity) - surface) / scale;
        let mut force_scene = self.god.update_with(&config, tip.translation, velocity, balls, &grids, scale);
        // Ridges: the spring's push along the surface normal becomes that of the ridged surface.
        let texture = material.and_then(|m| m.texture);
        if let (Some(t), Some(body)) = (texture, body.filter(|_| self.god.in_contact())) {
            let n = self.god.normal();
            let push = n * force_scene.dot(n).max(0.0);
            let ridged = t.apply(
                push,
                self.god.proxy(),
                (body.orientation, body.center_of_mass),
                config.stiffness_n_per_m / scale,
            );
            force_scene += ridged - push;
        }
        if let Some(object) = nearest.filter(|_| self.god.in_contact())
            && let Some(c) = self.object_contacts[..self.touched].iter_mut().find(|c| c.id == object.id)
        {
            c.touching = true;
            c.force = force_scene;
        }
        // A pushed object takes the opposite of the spring's force where the proxy rests on it.
        if let (Some(slot), Some(body)) = (nearest_slot.filter(|_| self.god.in_contact()), body)
            && let Some(pushed) = self.objects.get_mut(slot).and_then(Option::as_mut).and_then(|o| o.pushed.as_mut())
        {
            let lever = self.god.proxy() - body.center_of_mass;
            pushed.add_reaction(-force_scene, lever.cross(-force_scene));
        }
        let contact_device = self.map.wrench_to_device(ForceTorque { force: force_scene, torque: Vec3::ZERO });
        let before = tick.total();
        let requested = ForceTorque { force: before.force + contact_device.force, torque: before.torque };
        let out = self.safety.apply_at(requested, tick.dt_s, used.age_s(), device.pose.translation);
        tick.set(out);
        let proxy_pose = Pose::new(self.god.proxy(), tip.rotation);
        let reach = self.god.proxy().distance(tip.translation) + self.proxy.margin + self.proxy.tip_radius;
        self.tool.set_with_reach(tip, device.timestamp_us, reach);
        self.step_pushed(device.timestamp_us, tick.dt_s);
        self.report(device, out, contact_device.force, tip.translation, proxy_pose, used);
    }

    /// Records the tick's force sample and publishes the telemetry.
    fn report(
        &mut self,
        device: DeviceState,
        out: ForceTorque,
        contact_force: Vec3,
        tool_position: Vec3,
        tool_pose: Pose,
        used: Used,
    ) {
        let Used { contacts, sequence, age_us } = used;
        let _ = self.samples.push(ForceSample {
            t_us: device.timestamp_us,
            force: out.force,
            torque: out.torque,
            contact_force,
            tool_position,
            contacts,
            data_age_us: age_us.min(u32::MAX as u64) as u32,
            collision_sequence: sequence,
        });
        self.telemetry.write(RigTelemetry {
            object_contacts: self.object_contacts,
            object_count: self.touched as u32,
            device,
            tool_pose,
            output: out,
            contacts,
            collision_sequence: sequence,
            data_age_us: age_us,
            safety_phase: self.safety.phase(),
            safety_gain: self.safety.gain(),
            outside_workspace: self.safety.outside_workspace(),
            safety: self.safety.stats(),
        });
    }
}

/// The contact data a tick used: how many contacts (or spheres near the tip), the collision step's
/// sequence, and its age in µs.
#[derive(Clone, Copy)]
struct Used {
    contacts: u32,
    sequence: u64,
    age_us: u64,
}

/// The scene watcher's data as published (its step, the tool pose's time, its size), and how many
/// objects are watched, since when (device time).
struct Published {
    sequence: u64,
    timestamp_us: u64,
    contacts: usize,
    watched: usize,
    since_us: u64,
}

impl Published {
    /// The data used at `now_us`: its age is that of the tool pose the scene watcher's last step rests
    /// on; before its first step, the time since an object was first watched (so placing an object
    /// does not trip the watchdog unless the collision thread stays silent past it); 0 with nothing
    /// watched (no data can be stale).
    fn at(&self, now_us: u64) -> Used {
        let age_us = match (self.watched, self.sequence) {
            (0, _) => 0,
            (_, 0) => now_us.saturating_sub(self.since_us),
            _ => now_us.saturating_sub(self.timestamp_us),
        };
        Used { contacts: self.contacts as u32, sequence: self.sequence, age_us }
    }
}

impl Used {
    /// The data's age for the safety layer's watchdog, seconds.
    fn age_s(&self) -> f32 {
        self.age_us as f32 * 1e-6
    }
}
