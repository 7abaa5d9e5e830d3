//! The collision thread and the handles that steer it, feed it poses and read its results.
//!
//! [`pipeline`] makes the two ends: the [`CollisionHandle`] (any thread: objects, watchers, region,
//! pause, timings) and the [`CollisionStepper`] (the world with its command ring; steps once per call).
//! [`CollisionThread`] runs a stepper on its own thread, paced by a [`Pacer`]; tests and lockstep
//! simulations call the stepper by hand.

use super::scene::{PairSummary, SceneContacts};
use super::track::PoseTrack;
use super::world::{
    CollisionConfig, CollisionWorld, Command, NearSpheres, ObjectId, ObjectPose, Retired, StepReport, TimedPose,
    WatcherId, WatcherOutput,
};
use crate::bounding_volume::Aabb;
use crate::partitioning::InnerSphereTree;
use crate::shape::{SignedDistanceGrid, SurfaceShell};
use haptic_common::{ContactSet, Delegator, OnCollision, Pose};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Writes an object's latest pose (lock-free); give it to whichever thread moves the object.
pub struct PoseWriter {
    id: ObjectId,
    input: triple_buffer::Input<ObjectPose>,
}

impl PoseWriter {
    /// The object this writer moves.
    pub fn id(&self) -> ObjectId {
        self.id
    }

    /// Publishes a new pose sampled at `timestamp_us`. Never blocks or allocates.
    pub fn set(&mut self, pose: Pose, timestamp_us: u64) {
        self.input.write(TimedPose { pose, timestamp_us, reach: 0.0 }.into());
    }

    /// Publishes a new pose with the reach of the near watchers whose A object this is.
    pub fn set_with_reach(&mut self, pose: Pose, timestamp_us: u64, reach: f32) {
        self.input.write(TimedPose { pose, timestamp_us, reach }.into());
    }

    /// Publishes a moving object's last poses with their times (on the stepper's clock): each step
    /// reads the track at its own time. Never blocks or allocates.
    pub fn set_track(&mut self, track: &PoseTrack) {
        self.input.write(ObjectPose::Track(*track));
    }
}

/// Reads a watched pair's latest result (lock-free); give it to the force thread.
pub struct WatcherReader<T: Send> {
    id: WatcherId,
    output: triple_buffer::Output<T>,
}

/// Reads a watcher's overlapping sphere pairs.
pub type ContactReader = WatcherReader<ContactSet>;
/// Reads a near watcher's spheres (or a scene near watcher's).
pub type NearReader = WatcherReader<NearSpheres>;
/// Reads a scene watcher's contacts.
pub type SceneReader = WatcherReader<SceneContacts>;
/// Reads a summary watcher's overlap.
pub type SummaryReader = WatcherReader<PairSummary>;

impl<T: Send> WatcherReader<T> {
    /// The watcher this reader belongs to.
    pub fn id(&self) -> WatcherId {
        self.id
    }

    /// The newest published result (sequence 0 before the first step). Never blocks or allocates.
    pub fn latest(&mut self) -> &T {
        self.output.read()
    }
}

/// Timing and size of one collision step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTiming {
    /// Step counter.
    pub sequence: u64,
    /// Start on the stepper's clock, µs.
    pub start_us: u64,
    /// Time since the previous step's start, µs (0 for the first).
    pub period_us: u32,
    /// Time spent applying commands and querying, µs.
    pub work_us: u32,
    /// Part of it spent reading poses and in the broad phase, ns.
    pub broad_ns: u32,
    /// Watched pairs queried.
    pub queried: u32,
    /// Watched pairs the broad phase found apart.
    pub culled: u32,
    /// Contacts (or near spheres) found.
    pub contacts: u32,
    /// True when the budget cut a query short.
    pub budget_hit: bool,
}

/// When the collision thread steps, and on which clock its timings are read.
pub trait Pacer: Send + 'static {
    /// Runs once on the collision thread before its first step (e.g. to raise its priority).
    fn start(&mut self) {}
    /// Returns when the next step is due.
    fn wait(&mut self);
    /// Now on the clock of the step timings, µs.
    fn now_us(&self) -> u64;
}

/// A [`Pacer`] that sleeps to a fixed period, on a clock started with it.
pub struct FixedRate {
    epoch: Instant,
    period: Duration,
    next: Instant,
}

impl FixedRate {
    /// Steps every `period`.
    pub fn new(period: Duration) -> Self {
        let epoch = Instant::now();
        Self { epoch, period, next: epoch }
    }
}

impl Pacer for FixedRate {
    fn wait(&mut self) {
        self.next += self.period;
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
        } else {
            self.next = now;
        }
    }

    fn now_us(&self) -> u64 {
        self.epoch.elapsed().as_micros() as u64
    }
}

/// The world with the receiving ends of its rings: one call, one step.
pub struct CollisionStepper {
    world: CollisionWorld,
    incoming: rtrb::Consumer<Command>,
    retire: rtrb::Producer<Retired>,
    timings: rtrb::Producer<StepTiming>,
    leaked: Arc<AtomicU64>,
    steps: Arc<AtomicU64>,
    budget: Duration,
    last_start_us: Option<u64>,
}

impl CollisionStepper {
    /// Applies the pending commands, then checks every watched pair once; the step starts at `start_us`
    /// on the caller's clock, `now_us` reads that clock at its end. With `budgeted`, the queries stop
    /// refining at the configured step budget; without, they are exact (deterministic). Never allocates,
    /// frees, locks or logs.
    pub fn step(&mut self, start_us: u64, budgeted: bool, now_us: impl Fn() -> u64) -> StepReport {
        let start = Instant::now();
        let (retire, leaked) = (&mut self.retire, &self.leaked);
        while let Ok(command) = self.incoming.pop() {
            self.world.apply(command, &mut |r| {
                // Unreachable (see the ring's size in `pipeline`); were it full, leak rather than free here.
                if let Err(rtrb::PushError::Full(r)) = retire.push(r) {
                    leaked.fetch_add(1, Ordering::Relaxed);
                    std::mem::forget(r);
                }
            });
        }
        if self.world.paused() {
            return StepReport::default();
        }
        let report = self.world.step(start_us, budgeted.then(|| start + self.budget));
        let end_us = now_us().max(start_us);
        let period_us = self.last_start_us.map_or(0, |s| start_us.saturating_sub(s)) as u32;
        self.last_start_us = Some(start_us);
        let _ = self.timings.push(StepTiming {
            sequence: self.world.sequence(),
            start_us,
            period_us,
            work_us: (end_us - start_us) as u32,
            broad_ns: report.broad_ns,
            queried: report.queried,
            culled: report.culled,
            contacts: report.contacts,
            budget_hit: report.budget_hit,
        });
        self.steps.fetch_add(1, Ordering::Release);
        report
    }
}

/// Steers a collision world; when it runs on a [`CollisionThread`], dropping the handle stops and joins
/// the thread.
pub struct CollisionHandle {
    commands: rtrb::Producer<Command>,
    retired: rtrb::Consumer<Retired>,
    timings: rtrb::Consumer<StepTiming>,
    collected: u64,
    leaked: Arc<AtomicU64>,
    free_objects: Vec<u32>,
    free_watchers: Vec<u32>,
    steps: Arc<AtomicU64>,
    thread: Option<(Arc<AtomicBool>, JoinHandle<()>)>,
}

/// The two ends of a collision world: the handle that steers it and the stepper that runs it. Every
/// non-empty contact set is broadcast to `on_collision` on the stepping thread.
pub fn pipeline(config: &CollisionConfig, on_collision: Delegator<OnCollision>) -> (CollisionHandle, CollisionStepper) {
    let (commands, incoming) = rtrb::RingBuffer::new(config.command_capacity);
    // The return ring cannot fill: a command retires at most one item, and every handle method that
    // sends one that can retire anything first empties the ring; so at most the commands still queued
    // at that moment (<= command_capacity) plus the one sent after it retire before the next emptying.
    let (retire, retired) = rtrb::RingBuffer::new(config.command_capacity + config.max_objects + config.max_watchers);
    let (timings_tx, timings) = rtrb::RingBuffer::new(config.timing_capacity.max(1));
    let steps = Arc::new(AtomicU64::new(0));
    let leaked = Arc::new(AtomicU64::new(0));
    let stepper = CollisionStepper {
        world: CollisionWorld::with_delegates(config, on_collision),
        incoming,
        retire,
        timings: timings_tx,
        leaked: leaked.clone(),
        steps: steps.clone(),
        budget: config.step_budget,
        last_start_us: None,
    };
    let handle = CollisionHandle {
        commands,
        retired,
        timings,
        collected: 0,
        leaked,
        free_objects: (0..config.max_objects as u32).rev().collect(),
        free_watchers: (0..config.max_watchers as u32).rev().collect(),
        steps,
        thread: None,
    };
    (handle, stepper)
}

/// Starts collision threads.
pub struct CollisionThread;

impl CollisionThread {
    /// Spawns the thread, which steps every `config.period` with `config.step_budget` per step.
    pub fn spawn(config: CollisionConfig) -> std::io::Result<CollisionHandle> {
        let pacer = FixedRate::new(config.period);
        Self::spawn_with(&config, Delegator::new(), pacer)
    }

    /// Spawns the thread ("collision"), which steps whenever `pacer` says, with `config.step_budget`
    /// per step, broadcasting contacts to `on_collision`.
    pub fn spawn_with(
        config: &CollisionConfig,
        on_collision: Delegator<OnCollision>,
        mut pacer: impl Pacer,
    ) -> std::io::Result<CollisionHandle> {
        let (mut handle, mut stepper) = pipeline(config, on_collision);
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = std::thread::Builder::new().name("collision".into()).spawn(move || {
            pacer.start();
            while !stop2.load(Ordering::Acquire) {
                pacer.wait();
                stepper.step(pacer.now_us(), true, || pacer.now_us());
            }
        })?;
        handle.thread = Some((stop, thread));
        Ok(handle)
    }
}

impl CollisionHandle {
    /// Adds an object at `pose` (a moving one: its pose ages until written again); returns its pose
    /// writer, or `None` when all slots or the command ring are full.
    pub fn add_object(&mut self, tree: Arc<InnerSphereTree>, pose: Pose) -> Option<PoseWriter> {
        self.add_object_at(tree, TimedPose { pose, timestamp_us: 0, reach: 0.0 })
    }

    /// Adds an object with its first timed pose (`timestamp_us: u64::MAX` for one that never moves).
    pub fn add_object_at(&mut self, tree: Arc<InnerSphereTree>, pose: TimedPose) -> Option<PoseWriter> {
        self.collect_retired();
        let id = ObjectId(self.free_objects.pop()?);
        let (input, output) = triple_buffer::triple_buffer(&ObjectPose::Timed(pose));
        if self.commands.push(Command::AddObject(id, tree, output)).is_err() {
            self.free_objects.push(id.0);
            return None;
        }
        Some(PoseWriter { id, input })
    }

    /// Gives an object a new tree (e.g. a new tool). False when the command ring is full.
    pub fn set_tree(&mut self, id: ObjectId, tree: Arc<InnerSphereTree>) -> bool {
        self.collect_retired();
        self.commands.push(Command::SetTree(id, tree)).is_ok()
    }

    /// Gives object `id` a distance grid of its surface, built from the mesh its tree was built from
    /// (`None` takes it away): from the next step, pairs watching it as B measure A's spheres against
    /// its surface (`overlap_field_budgeted`: for a tool much smaller than the object, see
    /// docs/collette.md). False when the command ring is full.
    pub fn set_surface(&mut self, id: ObjectId, surface: Option<Arc<SignedDistanceGrid>>) -> bool {
        self.collect_retired();
        self.commands.push(Command::SetSurface(id, surface)).is_ok()
    }

    /// Gives object `id` its surface shell, split from the mesh its tree was built from (`None` takes it
    /// away): from the next step, pairs watching it as A against a B with a surface grid measure A's
    /// surface against B's (`overlap_shell_budgeted`: exact on flat faces at any depth, see
    /// docs/collette.md); when A has a grid and B a shell too, both surfaces
    /// (`overlap_surfaces_budgeted`: exact past the middle of B's thin parts as well). False when the
    /// command ring is full.
    pub fn set_shell(&mut self, id: ObjectId, shell: Option<Arc<SurfaceShell>>) -> bool {
        self.collect_retired();
        self.commands.push(Command::SetShell(id, shell)).is_ok()
    }

    /// Removes an object (its watchers then publish empty sets). False when the command ring is full.
    ///
    /// Its slot is reused by the next `add_object`: remove the object's watchers first.
    pub fn remove_object(&mut self, id: ObjectId) -> bool {
        self.collect_retired();
        let ok = self.commands.push(Command::RemoveObject(id)).is_ok();
        if ok && !self.free_objects.contains(&id.0) {
            self.free_objects.push(id.0);
        }
        ok
    }

    /// Watches the pair (A = tool, B = touched object); returns the reader of its contacts.
    pub fn add_watcher(&mut self, a: ObjectId, b: ObjectId) -> Option<ContactReader> {
        self.add_any_watcher(a, b, ContactSet::new(), |input| WatcherOutput::Contacts(Box::new(input)))
    }

    /// Watches B's spheres near A's origin (A = a point tool, its reach set with its pose); returns the
    /// reader of the spheres.
    pub fn add_near_watcher(&mut self, a: ObjectId, b: ObjectId) -> Option<NearReader> {
        self.add_any_watcher(a, b, NearSpheres::default(), |input| WatcherOutput::Near(Box::new(input)))
    }

    /// Watches A against every other object (a tool against a scene): each step queries the objects
    /// whose bounds touch A's and publishes all their contacts, grouped by object.
    pub fn add_scene_watcher(&mut self, a: ObjectId) -> Option<SceneReader> {
        self.add_any_watcher(a, a, SceneContacts::default(), |input| WatcherOutput::SceneContacts(Box::new(input)))
    }

    /// Watches every other object's spheres near A's origin (A = a point tool, its reach set with its
    /// pose); each sphere names its object.
    pub fn add_scene_near_watcher(&mut self, a: ObjectId) -> Option<NearReader> {
        self.add_any_watcher(a, a, NearSpheres::default(), |input| WatcherOutput::SceneNear(Box::new(input)))
    }

    /// Watches whether and how much A and B overlap, without their contacts (a few bytes a watcher
    /// instead of a contact set's 128 kB).
    pub fn add_summary_watcher(&mut self, a: ObjectId, b: ObjectId) -> Option<SummaryReader> {
        self.add_any_watcher(a, b, PairSummary::default(), |input| WatcherOutput::Summary(Box::new(input)))
    }

    fn add_any_watcher<T: Clone + Send>(
        &mut self,
        a: ObjectId,
        b: ObjectId,
        empty: T,
        wrap: impl FnOnce(triple_buffer::Input<T>) -> WatcherOutput,
    ) -> Option<WatcherReader<T>> {
        self.collect_retired();
        let id = WatcherId(self.free_watchers.pop()?);
        let (input, output) = triple_buffer::triple_buffer(&empty);
        if self.commands.push(Command::AddWatcher(id, a, b, wrap(input))).is_err() {
            self.free_watchers.push(id.0);
            return None;
        }
        Some(WatcherReader { id, output })
    }

    /// Stops watching a pair. False when the command ring is full.
    pub fn remove_watcher(&mut self, id: WatcherId) -> bool {
        self.collect_retired();
        let ok = self.commands.push(Command::RemoveWatcher(id)).is_ok();
        if ok && !self.free_watchers.contains(&id.0) {
            self.free_watchers.push(id.0);
        }
        ok
    }

    /// Restricts checks to pairs whose objects touch `region` (`None`: no restriction).
    pub fn set_region(&mut self, region: Option<Aabb>) -> bool {
        self.commands.push(Command::SetRegion(region)).is_ok()
    }

    /// Pauses or resumes the steps (paused: nothing is published, so the readers' data ages).
    pub fn pause(&mut self, paused: bool) -> bool {
        self.commands.push(Command::Pause(paused)).is_ok()
    }

    /// Commands that can be queued right now (each method sends one).
    pub fn free_commands(&self) -> usize {
        self.commands.slots()
    }

    /// Steps completed so far.
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Acquire)
    }

    /// Moves the recorded step timings into `out`; returns how many.
    pub fn drain_timings(&mut self, out: &mut Vec<StepTiming>) -> usize {
        let n = self.timings.slots();
        out.extend((0..n).filter_map(|_| self.timings.pop().ok()));
        n
    }

    /// Frees what the thread handed back (also done by every other method).
    pub fn collect_retired(&mut self) {
        while let Ok(r) = self.retired.pop() {
            drop(r);
            self.collected += 1;
        }
    }

    /// Removed or replaced objects, trees and watchers handed back by the thread and freed here so far.
    pub fn collected(&self) -> u64 {
        self.collected
    }

    /// Items the thread could not hand back because the return ring was full (leaked, not freed on the
    /// thread). Always 0: the ring is sized so that it cannot fill.
    pub fn leaked(&self) -> u64 {
        self.leaked.load(Ordering::Relaxed)
    }
}

impl Drop for CollisionHandle {
    fn drop(&mut self) {
        if let Some((stop, thread)) = self.thread.take() {
            stop.store(true, Ordering::Release);
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::box_buffers;
    use crate::{BuildOptions, QueryWorkspace, TriMesh, build};
    use glam::Vec3;
    use std::time::Duration;

    fn wait_for(reader: &mut ContactReader, what: impl Fn(&ContactSet) -> bool) -> bool {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if what(reader.latest()) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        false
    }

    #[test]
    fn everything_removed_comes_back_to_the_handle_even_with_the_command_ring_kept_full() {
        let (v, t) = box_buffers(Vec3::splat(0.5));
        let tree = Arc::new(
            build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(20), &mut |_| {}).expect("builds").0,
        );
        let config = CollisionConfig { command_capacity: 8, max_objects: 4, max_watchers: 2, ..Default::default() };
        let mut handle = CollisionThread::spawn(config).expect("spawns");
        let anchor = handle.add_object(tree.clone(), Pose::IDENTITY).expect("slot");
        let (mut sent, mut removals) = (0u64, 0u64);
        let start = Instant::now();
        // Add and remove objects and watchers as fast as the command ring takes them, with the region
        // commands (which never wait for the return ring to be emptied) in between.
        while sent < 3000 && start.elapsed() < Duration::from_secs(20) {
            let Some(object) = handle.add_object(tree.clone(), Pose::from_translation(Vec3::X * 0.5)) else {
                std::thread::yield_now();
                continue;
            };
            let watcher = handle.add_watcher(anchor.id(), object.id());
            let _ = handle.set_region(None);
            if let Some(w) = watcher {
                while !handle.remove_watcher(w.id()) {
                    std::thread::yield_now();
                }
                removals += 1;
            }
            while !handle.remove_object(object.id()) {
                std::thread::yield_now();
            }
            removals += 1;
            sent += 1;
        }
        assert_eq!(sent, 3000, "the thread kept up");
        let until = Instant::now() + Duration::from_secs(10);
        while handle.collected() < removals && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(1));
            handle.collect_retired();
        }
        assert_eq!(handle.leaked(), 0, "the return ring never filled");
        assert_eq!(handle.collected(), removals, "every removed object and watcher was freed by the handle");
        assert_eq!(Arc::strong_count(&tree), 2, "only the test's and the anchor's copies are left");
    }

    #[test]
    fn a_stepper_by_hand_gathers_near_spheres_pauses_swaps_trees_and_times_its_steps() {
        let tree_of = |n| {
            let (v, t) = box_buffers(Vec3::splat(0.5));
            Arc::new(
                build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(n), &mut |_| {}).expect("builds").0,
            )
        };
        let (coarse, fine) = (tree_of(50), tree_of(400));
        let (mut handle, mut stepper) = pipeline(&CollisionConfig::default(), Delegator::new());
        let mut tip = handle.add_object(coarse.clone(), Pose::IDENTITY).expect("slot");
        let still = TimedPose { pose: Pose::IDENTITY, timestamp_us: u64::MAX, reach: 0.0 };
        let target = handle.add_object_at(coarse.clone(), still).expect("slot");
        let mut near = handle.add_near_watcher(tip.id(), target.id()).expect("slot");
        let point = Vec3::new(0.0, 0.6, 0.0); // 0.1 above the box's top face
        tip.set_with_reach(Pose::from_translation(point), 40, 0.05);
        stepper.step(100, false, || 110);
        let set = near.latest();
        assert!(set.is_empty() && set.sequence == 1, "nothing within 0.05 of a point 0.1 away");
        assert_eq!(set.timestamp_us, 40, "a still object's pose never ages: the pair's time is the tip's");
        tip.set_with_reach(Pose::from_translation(point), 50, 0.3);
        stepper.step(200, false, || 230);
        let set = near.latest();
        let coarse_count = set.len();
        assert!(coarse_count > 0 && set.sequence == 2 && set.timestamp_us == 50);
        assert!(set.as_slice().iter().all(|s| s.center.distance(point) - s.radius <= 0.3 + 1e-5), "all within reach");
        assert!(handle.pause(true));
        assert_eq!(stepper.step(300, false, || 310), StepReport::default(), "a paused step does nothing");
        assert_eq!(near.latest().sequence, 2, "and publishes nothing");
        assert!(handle.pause(false) && handle.set_tree(target.id(), fine));
        stepper.step(400, false, || 450);
        let set = near.latest();
        assert!(
            set.sequence == 3 && set.len() != coarse_count,
            "the finer tree's spheres: {} vs {coarse_count}",
            set.len()
        );
        handle.collect_retired();
        assert_eq!(handle.collected(), 1, "the replaced tree came back to be freed");
        assert_eq!(Arc::strong_count(&coarse), 2, "held by the test and the tip only");
        let mut timings = Vec::new();
        assert_eq!(handle.drain_timings(&mut timings), 3, "three steps ran");
        let starts: Vec<_> = timings.iter().map(|t| (t.start_us, t.period_us, t.work_us)).collect();
        assert_eq!(starts, vec![(100, 0, 10), (200, 100, 30), (400, 200, 50)]);
        assert_eq!(handle.steps(), 3);
    }

    #[test]
    fn a_pair_whose_b_has_a_surface_grid_is_measured_against_it_until_it_is_taken_away() {
        let (v, t) = box_buffers(Vec3::new(1.0, 1.0, 0.5));
        let slab_mesh = TriMesh::new(v, t).expect("valid");
        let slab = Arc::new(build(&slab_mesh, &BuildOptions::spheres(300), &mut |_| {}).expect("builds").0);
        let grid = Arc::new(crate::SignedDistanceGrid::new(&slab_mesh, 40).expect("grid"));
        let (v, t) = box_buffers(Vec3::splat(0.1));
        let block = Arc::new(
            build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(300), &mut |_| {}).expect("builds").0,
        );
        let (mut handle, mut stepper) = pipeline(&CollisionConfig::default(), Delegator::new());
        let mut tool = handle.add_object(block.clone(), Pose::IDENTITY).expect("slot");
        let still = TimedPose { pose: Pose::IDENTITY, timestamp_us: u64::MAX, reach: 0.0 };
        let target = handle.add_object_at(slab.clone(), still).expect("slot");
        let mut contacts = handle.add_watcher(tool.id(), target.id()).expect("slot");
        // The block's lower 0.05 inside the slab's top face: 0.2 × 0.2 × 0.05 = 0.002.
        let pose = Pose::from_translation(Vec3::new(0.2, 0.1, 0.55));
        tool.set(pose, 10);
        let (mut ws, mut direct) = (QueryWorkspace::new(), ContactSet::new());
        let mut volume_at = |stepper: &mut CollisionStepper, start: u64| {
            stepper.step(start, false, || start + 5);
            contacts.latest().total_volume
        };
        let packed = volume_at(&mut stepper, 100);
        assert_eq!(packed, crate::overlap(&block, &pose, &slab, &Pose::IDENTITY, &mut ws, &mut direct).total_volume);
        assert!(handle.set_surface(target.id(), Some(grid.clone())));
        let surface = volume_at(&mut stepper, 200);
        let want = crate::overlap_field(&block, &pose, &slab, &grid, &Pose::IDENTITY, &mut ws, &mut direct);
        assert_eq!(surface, want.total_volume, "measured against the grid");
        assert!((surface / 0.002 - 1.0).abs() < 0.01, "the slice's true volume: {surface}");
        assert!(handle.set_surface(target.id(), None));
        assert_eq!(volume_at(&mut stepper, 300), packed, "back to two trees");
        handle.collect_retired();
        assert_eq!(handle.collected(), 1, "the grid came back to be freed");
        assert_eq!(Arc::strong_count(&grid), 1, "held by the test alone");
        // An object removed with its grid hands both back.
        assert!(handle.set_surface(target.id(), Some(grid.clone())));
        stepper.step(400, false, || 405);
        assert!(handle.remove_watcher(contacts.id()) && handle.remove_object(target.id()));
        stepper.step(500, false, || 505);
        handle.collect_retired();
        assert_eq!(Arc::strong_count(&grid), 1, "freed with its object");
        assert_eq!(handle.leaked(), 0);
    }

    #[test]
    fn handles_can_cross_threads() {
        fn is_send<T: Send>() {}
        is_send::<CollisionHandle>();
        is_send::<PoseWriter>();
        is_send::<ContactReader>();
    }

    #[test]
    fn the_thread_publishes_contacts_and_follows_poses_objects_and_regions() {
        let (v, t) = box_buffers(Vec3::splat(0.5));
        let tree = Arc::new(
            build(&TriMesh::new(v, t).expect("valid"), &BuildOptions::spheres(200), &mut |_| {}).expect("builds").0,
        );
        let mut handle = CollisionThread::spawn(CollisionConfig::default()).expect("spawns");
        let mut tool = handle.add_object(tree.clone(), Pose::from_translation(Vec3::X * 5.0)).expect("slot");
        let target = handle.add_object(tree.clone(), Pose::IDENTITY).expect("slot");
        let mut contacts = handle.add_watcher(tool.id(), target.id()).expect("slot");
        assert!(wait_for(&mut contacts, |s| s.sequence > 0 && s.is_empty()), "apart: no contact");
        tool.set(Pose::from_translation(Vec3::X * 0.5), 7);
        assert!(wait_for(&mut contacts, |s| s.total_volume > 0.05 && s.timestamp_us == 0), "overlap seen");
        let volume = contacts.latest().total_volume;
        let push: Vec3 = contacts.latest().as_slice().iter().map(|c| c.normal * c.volume).sum();
        assert!(push.x > 0.9 * push.length(), "normals push the tool (+x) out: {push}");
        handle.set_region(Some(Aabb::new(Vec3::splat(10.0), Vec3::splat(11.0))));
        assert!(wait_for(&mut contacts, |s| s.total_volume == 0.0), "outside the region nothing is checked");
        handle.set_region(None);
        assert!(wait_for(&mut contacts, |s| (s.total_volume - volume).abs() < 1e-3 * volume));
        assert!(handle.remove_object(target.id()));
        assert!(wait_for(&mut contacts, |s| s.is_empty() && s.total_volume == 0.0), "removed object: empty set");
        let third = handle.add_object(tree, Pose::from_translation(Vec3::X * 0.25)).expect("slot reused");
        let _w2 = handle.add_watcher(tool.id(), third.id()).expect("slot");
        assert!(handle.steps() > 0);
    }
}
