//! The collision core: objects, watched pairs and one step of checks (no thread, no clock of its own).

use crate::bounding_volume::Aabb;
use crate::partitioning::InnerSphereTree;
use crate::query::{Budget, QueryWorkspace, overlap_budgeted};
use haptic_common::{ContactSet, Pose};
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
    /// Sampling time, microseconds on the caller's clock.
    pub timestamp_us: u64,
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
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            max_objects: 64,
            max_watchers: 16,
            command_capacity: 256,
            period: Duration::from_millis(1),
            step_budget: Duration::from_micros(700),
        }
    }
}

/// Changes sent to the world (built on the caller's thread, applied without allocation).
pub enum Command {
    /// Puts a tree in slot `id`, with the reading end of its pose buffer.
    AddObject(ObjectId, Arc<InnerSphereTree>, triple_buffer::Output<TimedPose>),
    /// Empties slot `id`.
    RemoveObject(ObjectId),
    /// Watches the pair (A, B) in slot `id`, publishing into the writing end of its contact buffer.
    AddWatcher(WatcherId, ObjectId, ObjectId, Box<triple_buffer::Input<ContactSet>>),
    /// Stops watching slot `id`.
    RemoveWatcher(WatcherId),
    /// Only checks pairs whose objects' bounds touch this box (`None`: everywhere).
    SetRegion(Option<Aabb>),
}

/// What the world hands back to be freed off the real-time thread.
pub enum Retired {
    /// A removed object.
    Object(Arc<InnerSphereTree>, triple_buffer::Output<TimedPose>),
    /// A removed watcher.
    Watcher(Box<triple_buffer::Input<ContactSet>>),
}

struct ObjectSlot {
    tree: Arc<InnerSphereTree>,
    pose: triple_buffer::Output<TimedPose>,
}

struct WatcherSlot {
    a: ObjectId,
    b: ObjectId,
    out: Box<triple_buffer::Input<ContactSet>>,
}

/// Objects, watchers and the scratch memory of their queries.
pub struct CollisionWorld {
    objects: Vec<Option<ObjectSlot>>,
    watchers: Vec<Option<WatcherSlot>>,
    region: Option<Aabb>,
    workspace: QueryWorkspace,
    sequence: u64,
}

impl CollisionWorld {
    /// An empty world with all slots allocated.
    pub fn new(config: &CollisionConfig) -> Self {
        Self {
            objects: (0..config.max_objects).map(|_| None).collect(),
            watchers: (0..config.max_watchers).map(|_| None).collect(),
            region: None,
            workspace: QueryWorkspace::new(),
            sequence: 0,
        }
    }

    /// Applies a command; whatever it replaces or removes is passed to `retire` (never dropped here).
    pub fn apply(&mut self, command: Command, retire: &mut dyn FnMut(Retired)) {
        match command {
            Command::AddObject(id, tree, pose) => {
                if let Some(slot) = self.objects.get_mut(id.0 as usize) {
                    if let Some(old) = slot.replace(ObjectSlot { tree, pose }) {
                        retire(Retired::Object(old.tree, old.pose));
                    }
                } else {
                    retire(Retired::Object(tree, pose));
                }
            }
            Command::RemoveObject(id) => {
                if let Some(old) = self.objects.get_mut(id.0 as usize).and_then(Option::take) {
                    retire(Retired::Object(old.tree, old.pose));
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
        }
    }

    /// Checks every watched pair once and publishes its contacts; stops refining at `deadline` (each
    /// query gets an equal share of the time left and estimates what it did not traverse). Pairs outside the region or with a missing
    /// object publish an empty set. Returns the number of pairs queried.
    pub fn step(&mut self, deadline: Option<Instant>) -> usize {
        self.sequence += 1;
        for o in self.objects.iter_mut().flatten() {
            o.pose.update();
        }
        let mut queried = 0;
        let mut remaining = self.watchers.iter().flatten().count() as u32;
        for w in self.watchers.iter_mut().flatten() {
            // Each pair gets an equal share of what is left of the step, so one deep pair cannot starve the rest.
            let share = deadline.map(|d| {
                let now = Instant::now();
                now + d.saturating_duration_since(now) / remaining.max(1)
            });
            remaining = remaining.saturating_sub(1);
            let set = w.out.input_buffer_mut();
            set.clear();
            set.object_a = w.a.0;
            set.object_b = w.b.0;
            set.sequence = self.sequence;
            let (Some(Some(a)), Some(Some(b))) = (self.objects.get(w.a.0 as usize), self.objects.get(w.b.0 as usize))
            else {
                w.out.publish();
                continue;
            };
            let (pa, pb) = (*a.pose.output_buffer(), *b.pose.output_buffer());
            set.timestamp_us = pa.timestamp_us.min(pb.timestamp_us);
            let in_region = |tree: &InnerSphereTree, pose: &Pose| {
                self.region.is_none_or(|r| {
                    r.intersects_sphere(pose.transform_point(tree.root().bound.center), tree.root().bound.radius)
                })
            };
            if in_region(&a.tree, &pa.pose) && in_region(&b.tree, &pb.pose) {
                let budget = share.map_or(Budget::Unlimited, Budget::Deadline);
                overlap_budgeted(&a.tree, &pa.pose, &b.tree, &pb.pose, budget, &mut self.workspace, set);
                set.object_a = w.a.0;
                set.object_b = w.b.0;
                set.sequence = self.sequence;
                set.timestamp_us = pa.timestamp_us.min(pb.timestamp_us);
                queried += 1;
            }
            w.out.publish();
        }
        queried
    }
}
