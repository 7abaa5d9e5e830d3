//! The collision core: objects, watched pairs and one step of checks (no thread, no clock of its own):
//! each step reads every object's pose at the step's time, finds the objects whose bounds overlap (the
//! broad phase), and queries only the watched pairs among them.

use super::broad::BroadPhase;
use super::scene::{PairSummary, SceneContacts};
use super::track::PoseTrack;
use crate::bounding_volume::Aabb;
use crate::partitioning::InnerSphereTree;
use crate::query::{
    Budget, QueryWorkspace, overlap_budgeted, overlap_field_budgeted, overlap_shell_budgeted,
    overlap_surfaces_budgeted, spheres_near,
};
use crate::shape::{SignedDistanceGrid, SurfaceShell};
use glam::Vec3;
use haptic_common::{ContactSet, Delegator, OnCollision, Pose};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Identifier of an object in a collision world (index of its slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ObjectId(pub u32);

/// Identifier of a watched pair (index of its slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WatcherId(pub u32);

/// A pose with the time it was sampled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimedPose {
    /// World pose.
    pub pose: Pose,
    /// Sampling time, microseconds on the caller's clock; `u64::MAX` for an object that does not move
    /// (its pose never ages, so a pair's timestamp is its moving object's).
    pub timestamp_us: u64,
    /// For the A object of a near watcher: how far from its origin the partner's spheres are gathered,
    /// world units (0 otherwise).
    pub reach: f32,
}

/// What an object's pose buffer holds: a pose with its time (the tool, an object the game places), or
/// a moving object's [`PoseTrack`], read at each step's time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObjectPose {
    /// A pose sampled at a time (see [`TimedPose`]).
    Timed(TimedPose),
    /// The last poses of an object the game moves, with their times on the stepper's clock; the step
    /// uses the pose the track gives at its own time, which never ages (the game's pace is not a
    /// reason to fade forces out).
    Track(PoseTrack),
}

impl Default for ObjectPose {
    fn default() -> Self {
        ObjectPose::Timed(TimedPose::default())
    }
}

impl From<TimedPose> for ObjectPose {
    fn from(pose: TimedPose) -> Self {
        ObjectPose::Timed(pose)
    }
}

/// Most spheres a near watcher publishes per step (more are counted in `overflow`, not kept).
pub const MAX_NEAR_SPHERES: usize = 1024;

/// A sphere of an object near a point, in world coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NearSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
    /// The object whose sphere it is (its slot, as in [`ObjectId`]).
    pub object: u32,
}

/// What a near watcher publishes: the B object's inner spheres within reach of the A object's origin
/// (what a 3-DOF proxy at a point tool's tip needs), or for a scene near watcher every object's. Fixed
/// capacity, allocated once.
#[derive(Clone, Debug)]
pub struct NearSpheres {
    spheres: Box<[NearSphere]>,
    len: usize,
    /// Spheres found but not kept (the set was full even at the nearest reach tried).
    pub overflow: u32,
    /// The A object (the point).
    pub object_a: u32,
    /// The B object (whose spheres these are).
    pub object_b: u32,
    /// Step that produced the set (0: none yet).
    pub sequence: u64,
    /// Timestamp of the older of the two poses used, µs.
    pub timestamp_us: u64,
}

impl Default for NearSpheres {
    fn default() -> Self {
        Self {
            spheres: vec![NearSphere::default(); MAX_NEAR_SPHERES].into(),
            len: 0,
            overflow: 0,
            object_a: 0,
            object_b: 0,
            sequence: 0,
            timestamp_us: 0,
        }
    }
}

impl NearSpheres {
    /// Empties the set (keeps its memory).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = 0;
    }

    /// Adds a sphere; counts it as overflow when full.
    #[inline]
    pub fn push(&mut self, sphere: NearSphere) {
        if self.len == self.spheres.len() {
            self.overflow += 1;
        } else {
            self.spheres[self.len] = sphere;
            self.len += 1;
        }
    }

    /// The spheres.
    pub fn as_slice(&self) -> &[NearSphere] {
        &self.spheres[..self.len]
    }

    /// Number of spheres kept.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no sphere is near.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Sizes and timing of a collision world.
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionConfig {
    /// Object slots (default 64).
    pub max_objects: usize,
    /// Watcher slots (default 16).
    pub max_watchers: usize,
    /// Capacity of the command ring (default 256).
    pub command_capacity: usize,
    /// Period of the collision thread (default 1 ms).
    pub period: Duration,
    /// Time budget of one step for all watchers together (default 700 µs); each query is anytime.
    pub step_budget: Duration,
    /// Capacity of the step-timing ring (default 65 536; timings are dropped while it is full).
    pub timing_capacity: usize,
    /// Filter pairs by their bounds before querying them (default true); false queries every watched
    /// pair whose objects are present and inside the region, for comparison (`haptic-bench`).
    pub broad_phase: bool,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            max_objects: 64,
            max_watchers: 16,
            command_capacity: 256,
            period: Duration::from_millis(1),
            step_budget: Duration::from_micros(700),
            timing_capacity: 1 << 16,
            broad_phase: true,
        }
    }
}

/// Where a watcher publishes.
pub enum WatcherOutput {
    /// The overlapping sphere pairs of A and B (volumetric rendering).
    Contacts(Box<triple_buffer::Input<ContactSet>>),
    /// B's spheres within A's reach of A's origin (3-DOF proxy rendering).
    Near(Box<triple_buffer::Input<NearSpheres>>),
    /// Whether and how much A and B overlap (no contacts kept).
    Summary(Box<triple_buffer::Input<PairSummary>>),
    /// The overlapping sphere pairs of A and every other object (B unused): a tool against a scene.
    SceneContacts(Box<triple_buffer::Input<SceneContacts>>),
    /// Every other object's spheres within A's reach of A's origin (B unused).
    SceneNear(Box<triple_buffer::Input<NearSpheres>>),
}

impl WatcherOutput {
    /// True for the kinds that watch A against the whole scene.
    fn is_scene(&self) -> bool {
        matches!(self, WatcherOutput::SceneContacts(_) | WatcherOutput::SceneNear(_))
    }

    /// True for the kinds that gather spheres near A's origin.
    fn is_near(&self) -> bool {
        matches!(self, WatcherOutput::Near(_) | WatcherOutput::SceneNear(_))
    }
}

/// Changes sent to the world (built on the caller's thread, applied without allocation).
pub enum Command {
    /// Puts a tree in slot `id`, with the reading end of its pose buffer.
    AddObject(ObjectId, Arc<InnerSphereTree>, triple_buffer::Output<ObjectPose>),
    /// Gives the object in slot `id` a new tree (its pose buffer stays).
    SetTree(ObjectId, Arc<InnerSphereTree>),
    /// Gives the object in slot `id` a distance grid of its surface (`None`: takes it away): pairs that
    /// watch it as B then measure A's spheres against its surface (`overlap_field_budgeted`).
    SetSurface(ObjectId, Option<Arc<SignedDistanceGrid>>),
    /// Gives the object in slot `id` its surface shell (`None`: takes it away): pairs that watch it as A
    /// against a B with a surface grid then measure A's surface against B's (`overlap_shell_budgeted`),
    /// and both surfaces when A has a grid and B a shell too (`overlap_surfaces_budgeted`).
    SetShell(ObjectId, Option<Arc<SurfaceShell>>),
    /// Empties slot `id`.
    RemoveObject(ObjectId),
    /// Watches the pair (A, B) in slot `id` (for a scene output: A against every other object),
    /// publishing into the writing end of its buffer.
    AddWatcher(WatcherId, ObjectId, ObjectId, WatcherOutput),
    /// Stops watching slot `id`.
    RemoveWatcher(WatcherId),
    /// Only checks pairs whose objects' bounds touch this box (`None`: everywhere).
    SetRegion(Option<Aabb>),
    /// Pauses (true) or resumes the steps: a paused world publishes nothing, so readers see the data age.
    Pause(bool),
}

/// What the world hands back to be freed off the real-time thread.
pub enum Retired {
    /// A removed object (with its surface grid, if it had one).
    Object(Arc<InnerSphereTree>, triple_buffer::Output<ObjectPose>, Option<Arc<SignedDistanceGrid>>),
    /// A replaced tree.
    Tree(Arc<InnerSphereTree>),
    /// A replaced or taken surface grid.
    Surface(Arc<SignedDistanceGrid>),
    /// A replaced or taken surface shell (or a removed object's).
    Shell(Arc<SurfaceShell>),
    /// A removed watcher.
    Watcher(WatcherOutput),
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Pairs queried (inside the region, both objects present, their bounds overlapping).
    pub queried: u32,
    /// Watched pairs with both objects present that the broad phase found apart (not queried).
    pub culled: u32,
    /// Time spent reading poses and in the broad phase, ns.
    pub broad_ns: u32,
    /// Contacts (or near spheres) published over all pairs.
    pub contacts: u32,
    /// True when the deadline cut a query short.
    pub budget_hit: bool,
}

struct ObjectSlot {
    tree: Arc<InnerSphereTree>,
    pose: triple_buffer::Output<ObjectPose>,
    surface: Option<Arc<SignedDistanceGrid>>,
    shell: Option<Arc<SurfaceShell>>,
    /// The pose this step uses (read from `pose` at the step's time).
    now: TimedPose,
    /// A sphere holding the object in its own frame (see [`ObjectSlot::local_sphere`]), and where the
    /// step's pose puts it.
    local: (Vec3, f32),
    world: (Vec3, f32),
}

impl ObjectSlot {
    fn new(tree: Arc<InnerSphereTree>, pose: triple_buffer::Output<ObjectPose>) -> Self {
        let mut slot = Self {
            tree,
            pose,
            surface: None,
            shell: None,
            now: TimedPose::default(),
            local: (Vec3::ZERO, 0.0),
            world: (Vec3::ZERO, 0.0),
        };
        slot.local = slot.local_sphere();
        slot
    }

    /// A sphere holding the object in its frame: its tree's root bound, or with a surface grid the
    /// grid's box, or with a shell its surface's bound (the mesh's surface lies a little outside the
    /// inner spheres).
    fn local_sphere(&self) -> (Vec3, f32) {
        match (&self.surface, &self.shell) {
            (Some(grid), _) => (grid.bounds().center(), grid.bounds().extents().length() * 0.5),
            (None, Some(shell)) => shell.bound(),
            (None, None) => (self.tree.root().bound.center, self.tree.root().bound.radius),
        }
    }

    /// Reads the newest pose buffer at `at_us` into `now`, and where it puts the object's sphere (an
    /// empty track keeps the last pose).
    fn read_pose(&mut self, at_us: u64) {
        self.pose.update();
        match self.pose.output_buffer() {
            ObjectPose::Timed(timed) => self.now = *timed,
            ObjectPose::Track(track) => {
                if let Some(motion) = track.at(at_us) {
                    self.now = TimedPose { pose: motion.pose, timestamp_us: u64::MAX, reach: 0.0 };
                }
            }
        }
        self.world = (self.now.pose.transform_point(self.local.0), self.local.1);
    }

    /// Hands everything the slot holds to `retire`.
    fn retire(self, retire: &mut dyn FnMut(Retired)) {
        if let Some(shell) = self.shell {
            retire(Retired::Shell(shell));
        }
        retire(Retired::Object(self.tree, self.pose, self.surface));
    }

    /// The world sphere holding the object on this step.
    fn sphere(&self) -> (Vec3, f32) {
        self.world
    }

    /// The world box holding [`sphere`](Self::sphere) and, for a near watcher's point, its reach.
    fn bounds(&self) -> Aabb {
        let (center, radius) = self.sphere();
        let tree = Aabb::new(center - Vec3::splat(radius), center + Vec3::splat(radius));
        let (origin, reach) = (self.now.pose.translation, self.now.reach.max(0.0));
        let reach = Aabb::new(origin - Vec3::splat(reach), origin + Vec3::splat(reach));
        Aabb::new(tree.min.min(reach.min), tree.max.max(reach.max))
    }
}

struct WatcherSlot {
    a: ObjectId,
    b: ObjectId,
    out: WatcherOutput,
}

/// Objects, watchers and the scratch memory of their queries.
pub struct CollisionWorld {
    objects: Vec<Option<ObjectSlot>>,
    watchers: Vec<Option<WatcherSlot>>,
    broad: BroadPhase,
    /// False: every pair is queried (see [`CollisionConfig::broad_phase`]).
    broad_enabled: bool,
    region: Option<Aabb>,
    workspace: QueryWorkspace,
    /// One pair's contacts or near spheres, before they join a scene watcher's set.
    scratch: ContactSet,
    /// The objects a scene watcher queries on this step (a slot per object).
    candidates: Vec<u32>,
    scratch_near: NearSpheres,
    on_collision: Delegator<OnCollision>,
    paused: bool,
    sequence: u64,
}

impl CollisionWorld {
    /// An empty world with all slots allocated.
    pub fn new(config: &CollisionConfig) -> Self {
        Self::with_delegates(config, Delegator::new())
    }

    /// An empty world whose steps broadcast every non-empty contact set to `on_collision` (the paper's
    /// OnCollision; its delegates run on the stepping thread).
    pub fn with_delegates(config: &CollisionConfig, on_collision: Delegator<OnCollision>) -> Self {
        Self {
            objects: (0..config.max_objects).map(|_| None).collect(),
            watchers: (0..config.max_watchers).map(|_| None).collect(),
            broad: BroadPhase::new(config.max_objects),
            broad_enabled: config.broad_phase,
            region: None,
            workspace: QueryWorkspace::new(),
            scratch: ContactSet::new(),
            candidates: Vec::with_capacity(config.max_objects),
            scratch_near: NearSpheres::default(),
            on_collision,
            paused: false,
            sequence: 0,
        }
    }

    /// True while paused.
    pub fn paused(&self) -> bool {
        self.paused
    }

    /// Steps taken (the sequence number of the last published sets).
    pub fn sequence(&self) -> u64 {
        self.sequence
    }

    /// Applies a command; whatever it replaces or removes is passed to `retire` (never dropped here).
    pub fn apply(&mut self, command: Command, retire: &mut dyn FnMut(Retired)) {
        match command {
            Command::AddObject(id, tree, pose) => {
                if let Some(slot) = self.objects.get_mut(id.0 as usize) {
                    if let Some(old) = slot.replace(ObjectSlot::new(tree, pose)) {
                        old.retire(retire);
                    }
                } else {
                    retire(Retired::Object(tree, pose, None));
                }
            }
            Command::SetTree(id, tree) => match self.objects.get_mut(id.0 as usize).and_then(Option::as_mut) {
                Some(slot) => {
                    retire(Retired::Tree(std::mem::replace(&mut slot.tree, tree)));
                    slot.local = slot.local_sphere();
                }
                None => retire(Retired::Tree(tree)),
            },
            Command::SetSurface(id, surface) => {
                let slot = self.objects.get_mut(id.0 as usize).and_then(Option::as_mut);
                set_part(slot, surface, |slot| &mut slot.surface, Retired::Surface, retire);
            }
            Command::SetShell(id, shell) => {
                let slot = self.objects.get_mut(id.0 as usize).and_then(Option::as_mut);
                set_part(slot, shell, |slot| &mut slot.shell, Retired::Shell, retire);
            }
            Command::RemoveObject(id) => {
                if let Some(old) = self.objects.get_mut(id.0 as usize).and_then(Option::take) {
                    old.retire(retire);
                }
            }
            Command::AddWatcher(id, a, b, out) => {
                if let Some(slot) = self.watchers.get_mut(id.0 as usize) {
                    if let Some(old) = slot.replace(WatcherSlot { a, b, out }) {
                        retire(Retired::Watcher(old.out));
                    }
                } else {
                    retire(Retired::Watcher(out));
                }
            }
            Command::RemoveWatcher(id) => {
                if let Some(old) = self.watchers.get_mut(id.0 as usize).and_then(Option::take) {
                    retire(Retired::Watcher(old.out));
                }
            }
            Command::SetRegion(region) => self.region = region,
            Command::Pause(paused) => self.paused = paused,
        }
    }

    /// Checks every watched pair once at `at_us` (on the clock of the objects' tracks) and publishes its
    /// result; stops refining at `deadline` (each query gets an equal share of the time left and
    /// estimates what it did not traverse). Only pairs whose bounds overlap inside the region are
    /// queried; the others, and pairs with a missing object, publish an empty set. A paused world does
    /// nothing.
    pub fn step(&mut self, at_us: u64, deadline: Option<Instant>) -> StepReport {
        let mut report = StepReport::default();
        if self.paused {
            return report;
        }
        self.sequence += 1;
        let broad_start = Instant::now();
        let mut present = 0u32;
        for (slot, object) in self.objects.iter_mut().enumerate() {
            let bounds = object.as_mut().map(|o| {
                o.read_pose(at_us);
                o.bounds()
            });
            present += bounds.is_some() as u32;
            self.broad.set(slot, bounds);
        }
        if self.broad_enabled {
            self.broad.update();
        }
        report.broad_ns = broad_start.elapsed().as_nanos().min(u32::MAX as u128) as u32;
        let sequence = self.sequence;
        let Self {
            objects, watchers, broad, region, workspace, scratch, scratch_near, on_collision, candidates, ..
        } = self;
        let (objects, broad, region) = (&*objects, self.broad_enabled.then_some(&*broad), *region);
        let is_close = |ia: usize, ib: usize, near: bool| close(objects, broad, region, ia, ib, near);
        // Pairs to query this step, for the budget's shares.
        let mut remaining: u32 = watchers
            .iter()
            .flatten()
            .map(|w| match w.out.is_scene() {
                true => {
                    scene_candidates(objects, broad, region, w.a.0 as usize, w.out.is_near(), candidates);
                    candidates.len() as u32
                }
                false => is_close(w.a.0 as usize, w.b.0 as usize, w.out.is_near()) as u32,
            })
            .sum();
        // Each pair gets an equal share of what is left of the step, so one deep pair cannot starve the rest.
        let share = |remaining: &mut u32| {
            let d = deadline?;
            let now = Instant::now();
            let end = now + d.saturating_duration_since(now) / (*remaining).max(1);
            *remaining = remaining.saturating_sub(1);
            Some(end)
        };
        for w in watchers.iter_mut().flatten() {
            let ia = w.a.0 as usize;
            if w.out.is_scene() {
                let Some(Some(a)) = objects.get(ia) else {
                    publish_empty_scene(&mut w.out, w.a.0, sequence);
                    continue;
                };
                let mut oldest = a.now.timestamp_us;
                scene_candidates(objects, broad, region, ia, w.out.is_near(), candidates);
                report.culled += present.saturating_sub(1 + candidates.len() as u32);
                match &mut w.out {
                    WatcherOutput::SceneContacts(out) => {
                        let set = out.input_buffer_mut();
                        set.clear();
                        for &ib in candidates.iter() {
                            let Some(Some(b)) = objects.get(ib as usize) else { continue };
                            let budget = share(&mut remaining).map_or(Budget::Unlimited, Budget::Deadline);
                            report.budget_hit |= !measure(a, b, budget, workspace, scratch);
                            report.queried += 1;
                            oldest = oldest.min(b.now.timestamp_us);
                            (scratch.object_a, scratch.object_b, scratch.sequence) = (w.a.0, ib, sequence);
                            scratch.timestamp_us = a.now.timestamp_us.min(b.now.timestamp_us);
                            if !scratch.is_empty() {
                                on_collision.broadcast(scratch);
                            }
                            set.add(ib, scratch);
                        }
                        (set.object, set.sequence, set.timestamp_us) = (w.a.0, sequence, oldest);
                        report.contacts += set.contacts().len() as u32;
                        out.publish();
                    }
                    WatcherOutput::SceneNear(out) => {
                        let set = out.input_buffer_mut();
                        set.clear();
                        for &ib in candidates.iter() {
                            let Some(Some(b)) = objects.get(ib as usize) else { continue };
                            gather_near(b, a.now.pose.translation, a.now.reach, ib, workspace, scratch_near);
                            report.queried += 1;
                            oldest = oldest.min(b.now.timestamp_us);
                            set.overflow += scratch_near.overflow;
                            scratch_near.as_slice().iter().for_each(|s| set.push(*s));
                        }
                        (set.object_a, set.object_b) = (w.a.0, w.a.0);
                        (set.sequence, set.timestamp_us) = (sequence, oldest);
                        report.contacts += set.len() as u32;
                        out.publish();
                    }
                    _ => {}
                }
                continue;
            }
            let ib = w.b.0 as usize;
            let pair = match (objects.get(ia), objects.get(ib)) {
                (Some(Some(a)), Some(Some(b))) => Some((a, b)),
                _ => None,
            };
            let timestamp_us = pair.map_or(0, |(a, b)| a.now.timestamp_us.min(b.now.timestamp_us));
            let pair = if is_close(ia, ib, w.out.is_near()) {
                pair
            } else {
                report.culled += pair.is_some() as u32;
                None
            };
            report.queried += pair.is_some() as u32;
            let ids = (w.a.0, w.b.0);
            match &mut w.out {
                WatcherOutput::Contacts(out) => {
                    let set = out.input_buffer_mut();
                    set.clear();
                    if let Some((a, b)) = pair {
                        let budget = share(&mut remaining).map_or(Budget::Unlimited, Budget::Deadline);
                        report.budget_hit |= !measure(a, b, budget, workspace, set);
                    }
                    (set.object_a, set.object_b) = ids;
                    (set.sequence, set.timestamp_us) = (sequence, timestamp_us);
                    report.contacts += set.len() as u32;
                    if !set.is_empty() {
                        on_collision.broadcast(set);
                    }
                    out.publish();
                }
                WatcherOutput::Summary(out) => {
                    scratch.clear();
                    if let Some((a, b)) = pair {
                        let budget = share(&mut remaining).map_or(Budget::Unlimited, Budget::Deadline);
                        report.budget_hit |= !measure(a, b, budget, workspace, scratch);
                    }
                    let (object_a, object_b) = ids;
                    let (pairs, total_volume) = (scratch.len() as u32, scratch.total_volume);
                    out.write(PairSummary { object_a, object_b, pairs, total_volume, sequence, timestamp_us });
                }
                WatcherOutput::Near(out) => {
                    let set = out.input_buffer_mut();
                    set.clear();
                    if let Some((a, b)) = pair {
                        gather_near(b, a.now.pose.translation, a.now.reach, ids.1, workspace, set);
                    }
                    (set.object_a, set.object_b) = ids;
                    (set.sequence, set.timestamp_us) = (sequence, timestamp_us);
                    report.contacts += set.len() as u32;
                    out.publish();
                }
                WatcherOutput::SceneContacts(_) | WatcherOutput::SceneNear(_) => {}
            }
        }
        report
    }
}

/// Publishes an empty result (no pose, so time 0) for a scene watcher whose object is missing.
fn publish_empty_scene(out: &mut WatcherOutput, object: u32, sequence: u64) {
    match out {
        WatcherOutput::SceneContacts(out) => {
            let set = out.input_buffer_mut();
            set.clear();
            (set.object, set.sequence, set.timestamp_us) = (object, sequence, 0);
            out.publish();
        }
        WatcherOutput::SceneNear(out) => {
            let set = out.input_buffer_mut();
            set.clear();
            (set.sequence, set.timestamp_us) = (sequence, 0);
            out.publish();
        }
        _ => {}
    }
}

/// Puts in `out` the objects to query against object `ia` for a scene watcher (`near`: a near one): with
/// a broad phase, the objects whose boxes overlap its box and that pass [`close`]; without, every
/// present object inside the region. Allocation-free (`out` holds a slot per object).
fn scene_candidates(
    objects: &[Option<ObjectSlot>],
    broad: Option<&BroadPhase>,
    region: Option<Aabb>,
    ia: usize,
    near: bool,
    out: &mut Vec<u32>,
) {
    out.clear();
    match broad {
        Some(b) => b.near(ia, |ib| {
            if close(objects, broad, region, ia, ib, near) {
                out.push(ib as u32);
            }
        }),
        None => out.extend(
            (0..objects.len()).filter(|&ib| ib != ia && close(objects, None, region, ia, ib, near)).map(|ib| ib as u32),
        ),
    }
}

/// Puts `part` (a surface grid or shell) in `slot`'s field `field`, handing the one it replaces to
/// `retire` (or `part` itself when the slot is empty), and refits the slot's bounding sphere.
fn set_part<T>(
    slot: Option<&mut ObjectSlot>,
    part: Option<Arc<T>>,
    field: impl Fn(&mut ObjectSlot) -> &mut Option<Arc<T>>,
    retired: impl Fn(Arc<T>) -> Retired,
    retire: &mut dyn FnMut(Retired),
) {
    match slot {
        Some(slot) => {
            if let Some(old) = std::mem::replace(field(slot), part) {
                retire(retired(old));
            }
            slot.local = slot.local_sphere();
        }
        None => {
            if let Some(part) = part {
                retire(retired(part));
            }
        }
    }
}

/// A's spheres against B's tree, or against B's surface grid when it has one (A's surface when A has
/// a shell; both surfaces when both have a shell and a grid), into `set`; false when the budget cut the
/// query short.
fn measure(a: &ObjectSlot, b: &ObjectSlot, budget: Budget, ws: &mut QueryWorkspace, set: &mut ContactSet) -> bool {
    let (pa, pb) = (&a.now.pose, &b.now.pose);
    let result = match (b.surface.as_deref(), a.shell.as_deref(), a.surface.as_deref(), b.shell.as_deref()) {
        (Some(grid), Some(shell), Some(a_grid), Some(b_shell)) => {
            overlap_surfaces_budgeted(shell, a_grid, pa, b_shell, grid, pb, budget, ws, set)
        }
        (Some(grid), Some(shell), ..) => overlap_shell_budgeted(shell, pa, grid, pb, budget, ws, set),
        (Some(grid), None, ..) => overlap_field_budgeted(&a.tree, pa, &b.tree, grid, pb, budget, ws, set),
        (None, ..) => overlap_budgeted(&a.tree, pa, &b.tree, pb, budget, ws, set),
    };
    result.complete
}

/// Whether objects `ia` and `ib` must be queried: both present, their boxes overlapping (the broad
/// phase), their bounds close enough (`near`: B within A's reach of A's origin; otherwise the two
/// bounds touching), and both inside the region. Without a broad phase, every present pair inside the
/// region.
fn close(
    objects: &[Option<ObjectSlot>],
    broad: Option<&BroadPhase>,
    region: Option<Aabb>,
    ia: usize,
    ib: usize,
    near: bool,
) -> bool {
    let (Some(Some(a)), Some(Some(b))) = (objects.get(ia), objects.get(ib)) else { return false };
    let ((ca, ra), (cb, rb)) = (a.sphere(), b.sphere());
    let touching = match (broad, near) {
        (None, _) => true,
        (Some(broad), _) if !broad.overlaps(ia, ib) => false,
        (Some(_), true) => a.now.pose.translation.distance(cb) <= a.now.reach.max(0.0) + rb,
        (Some(_), false) => ca.distance(cb) <= ra + rb,
    };
    let inside = |(c, r): (Vec3, f32)| region.is_none_or(|box_| box_.intersects_sphere(c, r));
    touching && inside((ca, ra)) && inside((cb, rb))
}

/// Gathers object `b`'s spheres within `reach` of `point` into `set` (named `object`); when there are
/// more than it holds (a fine packing), gathers again nearer, so that the nearest are never the ones
/// left out.
fn gather_near(b: &ObjectSlot, point: Vec3, reach: f32, object: u32, ws: &mut QueryWorkspace, set: &mut NearSpheres) {
    let (tree, pose) = (&b.tree, &b.now.pose);
    let mut reach = reach;
    for _ in 0..4 {
        set.clear();
        spheres_near(tree, pose, point, reach, ws, |center, radius| set.push(NearSphere { center, radius, object }));
        if set.overflow == 0 {
            break;
        }
        reach *= 0.6;
    }
}
