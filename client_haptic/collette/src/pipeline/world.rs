//! The collision core: objects, watched pairs and one step of checks (no thread, no clock of its own).

use crate::bounding_volume::Aabb;
use crate::partitioning::InnerSphereTree;
use crate::query::{Budget, QueryWorkspace, overlap_budgeted, overlap_field_budgeted, spheres_near};
use crate::shape::SignedDistanceGrid;
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

/// Most spheres a near watcher publishes per step (more are counted in `overflow`, not kept).
pub const MAX_NEAR_SPHERES: usize = 1024;

/// A sphere of an object near a point, in world coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NearSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// What a near watcher publishes: the B object's inner spheres within reach of the A object's origin
/// (what a 3-DOF proxy at a point tool's tip needs). Fixed capacity, allocated once.
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
        }
    }
}

/// Where a watcher publishes.
pub enum WatcherOutput {
    /// The overlapping sphere pairs of A and B (volumetric rendering).
    Contacts(Box<triple_buffer::Input<ContactSet>>),
    /// B's spheres within A's reach of A's origin (3-DOF proxy rendering).
    Near(Box<triple_buffer::Input<NearSpheres>>),
}

/// Changes sent to the world (built on the caller's thread, applied without allocation).
pub enum Command {
    /// Puts a tree in slot `id`, with the reading end of its pose buffer.
    AddObject(ObjectId, Arc<InnerSphereTree>, triple_buffer::Output<TimedPose>),
    /// Gives the object in slot `id` a new tree (its pose buffer stays).
    SetTree(ObjectId, Arc<InnerSphereTree>),
    /// Gives the object in slot `id` a distance grid of its surface (`None`: takes it away): pairs that
    /// watch it as B then measure A's spheres against its surface (`overlap_field_budgeted`).
    SetSurface(ObjectId, Option<Arc<SignedDistanceGrid>>),
    /// Empties slot `id`.
    RemoveObject(ObjectId),
    /// Watches the pair (A, B) in slot `id`, publishing into the writing end of its buffer.
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
    Object(Arc<InnerSphereTree>, triple_buffer::Output<TimedPose>, Option<Arc<SignedDistanceGrid>>),
    /// A replaced tree.
    Tree(Arc<InnerSphereTree>),
    /// A replaced or taken surface grid.
    Surface(Arc<SignedDistanceGrid>),
    /// A removed watcher.
    Watcher(WatcherOutput),
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Pairs queried (inside the region, both objects present).
    pub queried: u32,
    /// Contacts (or near spheres) published over all pairs.
    pub contacts: u32,
    /// True when the deadline cut a query short.
    pub budget_hit: bool,
}

struct ObjectSlot {
    tree: Arc<InnerSphereTree>,
    pose: triple_buffer::Output<TimedPose>,
    surface: Option<Arc<SignedDistanceGrid>>,
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
    region: Option<Aabb>,
    workspace: QueryWorkspace,
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
            region: None,
            workspace: QueryWorkspace::new(),
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
                    if let Some(old) = slot.replace(ObjectSlot { tree, pose, surface: None }) {
                        retire(Retired::Object(old.tree, old.pose, old.surface));
                    }
                } else {
                    retire(Retired::Object(tree, pose, None));
                }
            }
            Command::SetTree(id, tree) => match self.objects.get_mut(id.0 as usize).and_then(Option::as_mut) {
                Some(slot) => retire(Retired::Tree(std::mem::replace(&mut slot.tree, tree))),
                None => retire(Retired::Tree(tree)),
            },
            Command::SetSurface(id, surface) => match self.objects.get_mut(id.0 as usize).and_then(Option::as_mut) {
                Some(slot) => {
                    if let Some(old) = std::mem::replace(&mut slot.surface, surface) {
                        retire(Retired::Surface(old));
                    }
                }
                None => {
                    if let Some(surface) = surface {
                        retire(Retired::Surface(surface));
                    }
                }
            },
            Command::RemoveObject(id) => {
                if let Some(old) = self.objects.get_mut(id.0 as usize).and_then(Option::take) {
                    retire(Retired::Object(old.tree, old.pose, old.surface));
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

    /// Checks every watched pair once and publishes its result; stops refining at `deadline` (each
    /// query gets an equal share of the time left and estimates what it did not traverse). Pairs outside
    /// the region or with a missing object publish an empty set. A paused world does nothing.
    pub fn step(&mut self, deadline: Option<Instant>) -> StepReport {
        let mut report = StepReport::default();
        if self.paused {
            return report;
        }
        self.sequence += 1;
        for o in self.objects.iter_mut().flatten() {
            o.pose.update();
        }
        let mut remaining = self.watchers.iter().flatten().count() as u32;
        for w in self.watchers.iter_mut().flatten() {
            // Each pair gets an equal share of what is left of the step, so one deep pair cannot starve the rest.
            let share = deadline.map(|d| {
                let now = Instant::now();
                now + d.saturating_duration_since(now) / remaining.max(1)
            });
            remaining = remaining.saturating_sub(1);
            let pair = match (self.objects.get(w.a.0 as usize), self.objects.get(w.b.0 as usize)) {
                (Some(Some(a)), Some(Some(b))) => Some(Pair::of(a, b, self.region)),
                _ => None,
            };
            let timestamp_us = pair.as_ref().map_or(0, |p| p.timestamp_us);
            let (ids, sequence) = ((w.a.0, w.b.0), self.sequence);
            match &mut w.out {
                WatcherOutput::Contacts(out) => {
                    let set = out.input_buffer_mut();
                    set.clear();
                    if let Some(Pair { a, pa, b, pb, b_surface, inside: true, .. }) = pair {
                        let budget = share.map_or(Budget::Unlimited, Budget::Deadline);
                        let ws = &mut self.workspace;
                        let result = match b_surface {
                            Some(grid) => overlap_field_budgeted(a, &pa.pose, b, grid, &pb.pose, budget, ws, set),
                            None => overlap_budgeted(a, &pa.pose, b, &pb.pose, budget, ws, set),
                        };
                        report.budget_hit |= !result.complete;
                        report.queried += 1;
                    }
                    (set.object_a, set.object_b) = ids;
                    (set.sequence, set.timestamp_us) = (sequence, timestamp_us);
                    report.contacts += set.len() as u32;
                    if !set.is_empty() {
                        self.on_collision.broadcast(set);
                    }
                    out.publish();
                }
                WatcherOutput::Near(out) => {
                    let set = out.input_buffer_mut();
                    set.clear();
                    if let Some(Pair { pa, b, pb, inside: true, .. }) = pair {
                        gather_near(b, &pb.pose, pa.pose.translation, pa.reach, &mut self.workspace, set);
                        report.queried += 1;
                    }
                    (set.object_a, set.object_b) = ids;
                    (set.sequence, set.timestamp_us) = (sequence, timestamp_us);
                    report.contacts += set.len() as u32;
                    out.publish();
                }
            }
        }
        report
    }
}

/// A watched pair whose two objects are present: their trees and latest poses, the older pose's time,
/// and whether both lie in the region.
struct Pair<'a> {
    a: &'a InnerSphereTree,
    pa: TimedPose,
    b: &'a InnerSphereTree,
    pb: TimedPose,
    b_surface: Option<&'a SignedDistanceGrid>,
    timestamp_us: u64,
    inside: bool,
}

impl<'a> Pair<'a> {
    fn of(a: &'a ObjectSlot, b: &'a ObjectSlot, region: Option<Aabb>) -> Self {
        let (pa, pb) = (*a.pose.output_buffer(), *b.pose.output_buffer());
        let inside = |tree: &InnerSphereTree, pose: &Pose| {
            region.is_none_or(|r| {
                r.intersects_sphere(pose.transform_point(tree.root().bound.center), tree.root().bound.radius)
            })
        };
        Self {
            a: &a.tree,
            pa,
            b: &b.tree,
            pb,
            b_surface: b.surface.as_deref(),
            timestamp_us: pa.timestamp_us.min(pb.timestamp_us),
            inside: inside(&a.tree, &pa.pose) && inside(&b.tree, &pb.pose),
        }
    }
}

/// Gathers `tree`'s spheres within `reach` of `point` into `set`; when there are more than it holds (a
/// fine packing), gathers again nearer, so that the nearest are never the ones left out.
fn gather_near(
    tree: &InnerSphereTree,
    pose: &Pose,
    point: Vec3,
    reach: f32,
    ws: &mut QueryWorkspace,
    set: &mut NearSpheres,
) {
    let mut reach = reach;
    for _ in 0..4 {
        set.clear();
        spheres_near(tree, pose, point, reach, ws, |center, radius| set.push(NearSphere { center, radius }));
        if set.overflow == 0 {
            break;
        }
        reach *= 0.6;
    }
}
