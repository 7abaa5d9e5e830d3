//! The collision thread and the handles that steer it, feed it poses and read its contacts.

use super::world::{CollisionConfig, CollisionWorld, Command, ObjectId, Retired, TimedPose, WatcherId};
use crate::bounding_volume::Aabb;
use crate::partitioning::InnerSphereTree;
use haptic_common::{ContactSet, Pose};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Instant;

/// Writes an object's latest pose (lock-free); give it to whichever thread moves the object.
pub struct PoseWriter {
    id: ObjectId,
    input: triple_buffer::Input<TimedPose>,
}

impl PoseWriter {
    /// The object this writer moves.
    pub fn id(&self) -> ObjectId {
        self.id
    }

    /// Publishes a new pose sampled at `timestamp_us`. Never blocks or allocates.
    pub fn set(&mut self, pose: Pose, timestamp_us: u64) {
        self.input.write(TimedPose { pose, timestamp_us });
    }
}

/// Reads a watched pair's latest contacts (lock-free); give it to the force thread.
pub struct ContactReader {
    id: WatcherId,
    output: triple_buffer::Output<ContactSet>,
}

impl ContactReader {
    /// The watcher this reader belongs to.
    pub fn id(&self) -> WatcherId {
        self.id
    }

    /// The newest published contact set (sequence 0 before the first step). Never blocks or allocates.
    pub fn latest(&mut self) -> &ContactSet {
        self.output.read()
    }
}

/// Steers a running collision thread; dropping it stops and joins the thread.
pub struct CollisionHandle {
    commands: rtrb::Producer<Command>,
    retired: rtrb::Consumer<Retired>,
    collected: u64,
    leaked: Arc<AtomicU64>,
    free_objects: Vec<u32>,
    free_watchers: Vec<u32>,
    stop: Arc<AtomicBool>,
    steps: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

/// Starts collision threads.
pub struct CollisionThread;

impl CollisionThread {
    /// Spawns the thread, which steps every `config.period` with `config.step_budget` per step.
    pub fn spawn(config: CollisionConfig) -> std::io::Result<CollisionHandle> {
        let (commands, mut incoming) = rtrb::RingBuffer::new(config.command_capacity);
        // The return ring cannot fill: a command retires at most one item, and every handle method that
        // sends one that can retire anything first empties the ring; so at most the commands still queued
        // at that moment (<= command_capacity) plus the one sent after it retire before the next emptying.
        let (mut retire_tx, retired) =
            rtrb::RingBuffer::new(config.command_capacity + config.max_objects + config.max_watchers);
        let stop = Arc::new(AtomicBool::new(false));
        let steps = Arc::new(AtomicU64::new(0));
        let leaked = Arc::new(AtomicU64::new(0));
        let mut world = CollisionWorld::new(&config);
        let (stop2, steps2, leaked2) = (stop.clone(), steps.clone(), leaked.clone());
        let thread = std::thread::Builder::new().name("collette".into()).spawn(move || {
            let mut next = Instant::now();
            while !stop2.load(Ordering::Acquire) {
                while let Ok(cmd) = incoming.pop() {
                    world.apply(cmd, &mut |r| {
                        // Unreachable (see the ring's size); were it full, leak rather than free here.
                        if let Err(rtrb::PushError::Full(r)) = retire_tx.push(r) {
                            leaked2.fetch_add(1, Ordering::Relaxed);
                            std::mem::forget(r);
                        }
                    });
                }
                world.step(Some(Instant::now() + config.step_budget));
                steps2.fetch_add(1, Ordering::Release);
                next += config.period;
                let now = Instant::now();
                if next > now {
                    std::thread::sleep(next - now);
                } else {
                    next = now;
                }
            }
        })?;
        Ok(CollisionHandle {
            commands,
            retired,
            collected: 0,
            leaked,
            free_objects: (0..config.max_objects as u32).rev().collect(),
            free_watchers: (0..config.max_watchers as u32).rev().collect(),
            stop,
            steps,
            thread: Some(thread),
        })
    }
}

impl CollisionHandle {
    /// Adds an object at `pose`; returns its pose writer, or `None` when all slots or the command ring are full.
    pub fn add_object(&mut self, tree: Arc<InnerSphereTree>, pose: Pose) -> Option<PoseWriter> {
        self.collect_retired();
        let id = ObjectId(self.free_objects.pop()?);
        let (input, output) = triple_buffer::triple_buffer(&TimedPose { pose, timestamp_us: 0 });
        if self.commands.push(Command::AddObject(id, tree, output)).is_err() {
            self.free_objects.push(id.0);
            return None;
        }
        Some(PoseWriter { id, input })
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
        self.collect_retired();
        let id = WatcherId(self.free_watchers.pop()?);
        let (input, output) = triple_buffer::triple_buffer(&ContactSet::new());
        if self.commands.push(Command::AddWatcher(id, a, b, Box::new(input))).is_err() {
            self.free_watchers.push(id.0);
            return None;
        }
        Some(ContactReader { id, output })
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

    /// Steps completed by the thread so far.
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Acquire)
    }

    /// Frees what the thread handed back (also done by every other method).
    pub fn collect_retired(&mut self) {
        while let Ok(r) = self.retired.pop() {
            drop(r);
            self.collected += 1;
        }
    }

    /// Removed or replaced objects and watchers handed back by the thread and freed here so far.
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
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::box_buffers;
    use crate::{BuildOptions, TriMesh, build};
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
