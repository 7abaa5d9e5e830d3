//! The game thread's end of the rig: what is watched, wired into collette's collision pipeline and the
//! force stage.
//!
//! You need this module to see how an object reaches both threads: its tree goes to the collision
//! pipeline (where the tool's one scene watcher finds it when their bounds touch: overlaps for
//! volumetric rendering, spheres near the tip for the proxy), its slot there with its material and
//! motion to the force stage. Both travel through fixed-capacity rings; whatever the threads replace or
//! remove comes back here to be freed.

use collette::pipeline::{
    CollisionHandle, ObjectId, PoseTrack, PoseWriter, SummaryReader, TimedPose, TrackTiming, WatcherId,
};
use forcecomp::BodyMotion;
use haptic_common::Pose;

use crate::force::{ForceCommand, Returned, WatchedObject};
use crate::push::PushedBody;
use crate::spec::{MAX_OBJECTS, MAX_PAIR_WATCHERS, ObjectSpec, PairContact, ToolSpec, center_of_mass};
use crate::{Result, RigError};

/// Capacity of the ring of changes to the force stage (a game moving every object each frame sends
/// one per object).
pub(crate) const FORCE_COMMANDS: usize = 1024;

/// A watched object's place in the collision pipeline.
struct Entry {
    id: u32,
    object: ObjectId,
    /// Moves the object on the collision thread (None: a pushed object, which the haptic thread moves).
    pose: Option<PoseWriter>,
    /// Its centre of mass in its own frame.
    center_of_mass: glam::Vec3,
    /// Its last poses with their times, while the game moves it (empty: placed).
    track: PoseTrack,
    /// Where the game last placed it (a track starts from there).
    placed: Pose,
}

/// A watcher between two objects, read on the game thread.
struct PairEntry {
    a: u32,
    b: u32,
    watcher: WatcherId,
    reader: SummaryReader,
}

impl PairEntry {
    fn joins(&self, id: u32) -> bool {
        self.a == id || self.b == id
    }
}

/// What the rig watches, and the ends of the rings that change it.
pub(crate) struct Scene {
    pub(crate) collision: CollisionHandle,
    tool: ObjectId,
    entries: Vec<Entry>,
    pairs: Vec<PairEntry>,
    forces: rtrb::Producer<ForceCommand>,
    garbage: rtrb::Consumer<Returned>,
    /// How moving objects' tracks are read.
    timing: TrackTiming,
    /// Objects freed since the last `collect_garbage` (the other methods free too, before sending).
    freed: usize,
}

impl Scene {
    /// A scene with only the tool (`tool`: its object in `collision`).
    pub(crate) fn new(
        collision: CollisionHandle,
        tool: ObjectId,
        forces: rtrb::Producer<ForceCommand>,
        garbage: rtrb::Consumer<Returned>,
        timing: TrackTiming,
    ) -> Self {
        let (entries, pairs) = (Vec::with_capacity(MAX_OBJECTS), Vec::with_capacity(MAX_PAIR_WATCHERS));
        Self { collision, tool, entries, pairs, forces, garbage, timing, freed: 0 }
    }

    /// Watches an object (replaces the one with the same id); with a mass, the tool pushes it (see
    /// [`crate::push`]).
    pub(crate) fn add_object(&mut self, spec: ObjectSpec, pushed_kg: Option<f32>) -> Result<()> {
        self.free_returned();
        if let Some(mass_kg) = pushed_kg.filter(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(RigError::BadMass { id: spec.id, mass_kg });
        }
        if self.forces.slots() == 0 {
            return Err(RigError::QueueFull("haptic"));
        }
        // All or nothing: removing a replaced object and adding this one take two commands, and its
        // watchers against other objects two each (taken down with it, set up again after).
        let paired = self.pairs.iter().filter(|p| p.joins(spec.id)).count();
        if self.collision.free_commands() < 2 + 2 * paired {
            return Err(RigError::QueueFull("collision"));
        }
        if self.forces.slots() < 2 {
            return Err(RigError::QueueFull("haptic"));
        }
        let mut rewatch = Vec::new();
        if let Some(i) = self.entries.iter().position(|e| e.id == spec.id) {
            rewatch = self.drop_pairs_of(spec.id);
            let old = self.entries.swap_remove(i);
            self.forget(&old)?;
        } else if self.entries.len() >= MAX_OBJECTS {
            return Err(RigError::TooManyObjects(MAX_OBJECTS));
        }
        let full = || RigError::QueueFull("collision");
        let still = TimedPose { pose: spec.pose, timestamp_us: u64::MAX, reach: 0.0 };
        let pose = self.collision.add_object_at(spec.tree.clone(), still).ok_or_else(full)?;
        let local_center = center_of_mass(&spec.tree);
        let motion = BodyMotion {
            orientation: spec.pose.rotation,
            ..BodyMotion::at_rest(spec.pose.transform_point(local_center))
        };
        let object_id = pose.id();
        // A pushed object's pose is written by the haptic thread, which moves it.
        let (pose, pushed) = match pushed_kg {
            Some(mass_kg) => (None, Some(PushedBody::new(&spec.tree, local_center, mass_kg, spec.pose, pose, spec.id))),
            None => (Some(pose), None),
        };
        let object = Box::new(WatchedObject {
            id: spec.id,
            slot: object_id.0,
            material: spec.material,
            motion,
            center_of_mass: local_center,
            track: None,
            pushed,
            surface: None,
        });
        self.forces.push(ForceCommand::Add(object)).map_err(|_| RigError::QueueFull("haptic"))?;
        let track = PoseTrack::new(self.timing);
        let placed = spec.pose;
        self.entries.push(Entry { id: spec.id, object: object_id, pose, center_of_mass: local_center, track, placed });
        for (a, b) in rewatch {
            self.watch_pair(a, b)?;
        }
        Ok(())
    }

    /// Watches objects `a` and `b` against each other (nothing happens for a pair already watched).
    pub(crate) fn watch_pair(&mut self, a: u32, b: u32) -> Result<()> {
        self.free_returned();
        if a == b {
            return Err(RigError::SamePair(a));
        }
        if self.pairs.iter().any(|p| p.joins(a) && p.joins(b)) {
            return Ok(());
        }
        if self.pairs.len() >= MAX_PAIR_WATCHERS {
            return Err(RigError::TooManyPairs(MAX_PAIR_WATCHERS));
        }
        let (oa, ob) = (self.object_of(a)?, self.object_of(b)?);
        let reader = self.collision.add_summary_watcher(oa, ob).ok_or(RigError::QueueFull("collision"))?;
        self.pairs.push(PairEntry { a, b, watcher: reader.id(), reader });
        Ok(())
    }

    /// Stops watching objects `a` and `b` against each other (nothing happens for a pair not watched).
    pub(crate) fn unwatch_pair(&mut self, a: u32, b: u32) -> Result<()> {
        self.free_returned();
        let Some(i) = self.pairs.iter().position(|p| p.joins(a) && p.joins(b) && a != b) else { return Ok(()) };
        if !self.collision.remove_watcher(self.pairs[i].watcher) {
            return Err(RigError::QueueFull("collision"));
        }
        self.pairs.swap_remove(i);
        Ok(())
    }

    /// Appends what every watcher between two objects saw on the latest collision step.
    pub(crate) fn pair_contacts(&mut self, out: &mut Vec<PairContact>) {
        for p in &mut self.pairs {
            let seen = p.reader.latest();
            out.push(PairContact {
                a: p.a,
                b: p.b,
                touching: seen.pairs > 0 || seen.total_volume > 0.0,
                pairs: seen.pairs,
                volume_m3: seen.total_volume,
                sequence: seen.sequence,
            });
        }
    }

    /// Takes down the watchers between object `id` and others (before the object goes); returns their
    /// pairs.
    fn drop_pairs_of(&mut self, id: u32) -> Vec<(u32, u32)> {
        let mut dropped = Vec::new();
        while let Some(i) = self.pairs.iter().position(|p| p.joins(id)) {
            let p = self.pairs.swap_remove(i);
            // The queue was checked for room by the caller.
            self.collision.remove_watcher(p.watcher);
            dropped.push((p.a, p.b));
        }
        dropped
    }

    /// Moves object `id` to `pose`: its pose buffer on the collision thread, its motion in the force stage.
    pub(crate) fn move_object(&mut self, id: u32, pose: Pose) -> Result<()> {
        self.free_returned();
        let entry = self.entries.iter_mut().find(|e| e.id == id).ok_or(RigError::UnknownObject(id))?;
        let command = ForceCommand::Move {
            slot: entry.object.0,
            center_of_mass: pose.transform_point(entry.center_of_mass),
            orientation: pose.rotation,
        };
        self.forces.push(command).map_err(|_| RigError::QueueFull("haptic"))?;
        // A placement, not a sample: it never ages (see `TimedPose`).
        if let Some(writer) = &mut entry.pose {
            writer.set(pose, u64::MAX);
        }
        entry.track.clear();
        entry.placed = pose;
        Ok(())
    }

    /// Adds the pose object `id` had at `t_us` (rig clock) to its track: both threads read the track at
    /// their own time, so the object moves smoothly between the game's frames, with its velocity.
    pub(crate) fn move_object_at(&mut self, id: u32, pose: Pose, t_us: u64) -> Result<()> {
        self.free_returned();
        let entry = self.entries.iter_mut().find(|e| e.id == id).ok_or(RigError::UnknownObject(id))?;
        let mut track = entry.track;
        if track.samples().is_empty() {
            // From rest where it was placed, not a jump to the first pose.
            track.push(entry.placed, t_us.saturating_sub(self.timing.delay_us as u64));
        }
        if !track.push(pose, t_us) {
            return Err(RigError::BadSample { id, t_us });
        }
        let command = ForceCommand::Track { slot: entry.object.0, track };
        self.forces.push(command).map_err(|_| RigError::QueueFull("haptic"))?;
        entry.track = track;
        if let Some(writer) = &mut entry.pose {
            writer.set_track(&track);
        }
        Ok(())
    }

    /// Stops watching object `id` (nothing happens for an id not watched).
    pub(crate) fn remove_object(&mut self, id: u32) -> Result<()> {
        self.free_returned();
        let Some(i) = self.entries.iter().position(|e| e.id == id) else { return Ok(()) };
        let paired = self.pairs.iter().filter(|p| p.joins(id)).count();
        if self.collision.free_commands() < 1 + paired {
            return Err(RigError::QueueFull("collision"));
        }
        if self.forces.slots() == 0 {
            return Err(RigError::QueueFull("haptic"));
        }
        self.drop_pairs_of(id);
        let old = self.entries.swap_remove(i);
        self.forget(&old)
    }

    /// Takes an object out of the force stage and the collision pipeline (room in both rings checked by
    /// the caller).
    fn forget(&mut self, entry: &Entry) -> Result<()> {
        self.forces.push(ForceCommand::Remove(entry.object.0)).map_err(|_| RigError::QueueFull("haptic"))?;
        if self.collision.remove_object(entry.object) { Ok(()) } else { Err(RigError::QueueFull("collision")) }
    }

    /// Replaces the tool's tree, centre of mass and material.
    pub(crate) fn set_tool(&mut self, tool: ToolSpec) -> Result<()> {
        self.free_returned();
        if self.forces.slots() == 0 {
            return Err(RigError::QueueFull("haptic"));
        }
        // The tree, the shell and the grid (or none: an old tool's would be wrong) together.
        if self.collision.free_commands() < 3 {
            return Err(RigError::QueueFull("collision"));
        }
        if !self.collision.set_tree(self.tool, tool.tree)
            || !self.collision.set_shell(self.tool, tool.shell)
            || !self.collision.set_surface(self.tool, tool.surface)
        {
            return Err(RigError::QueueFull("collision"));
        }
        let command = ForceCommand::SetTool { center_of_mass: tool.center_of_mass, material: tool.material };
        self.forces.push(command).map_err(|_| RigError::QueueFull("haptic"))
    }

    /// Measures the tool against object `id`'s surface grid (`None`: against its tree again).
    pub(crate) fn set_surface(
        &mut self,
        id: u32,
        surface: Option<std::sync::Arc<collette::SignedDistanceGrid>>,
    ) -> Result<()> {
        self.free_returned();
        let object = self.object_of(id)?;
        if self.forces.slots() == 0 {
            return Err(RigError::QueueFull("haptic"));
        }
        if !self.collision.set_surface(object, surface.clone()) {
            return Err(RigError::QueueFull("collision"));
        }
        // The 3-DOF proxy holds the tip on the grid (on the haptic thread).
        let command = ForceCommand::Surface { slot: object.0, grid: surface };
        self.forces.push(command).map_err(|_| RigError::QueueFull("haptic"))
    }

    /// Gives object `id` its surface shell (`None`: takes it away).
    pub(crate) fn set_object_shell(
        &mut self,
        id: u32,
        shell: Option<std::sync::Arc<collette::SurfaceShell>>,
    ) -> Result<()> {
        self.free_returned();
        let object = self.object_of(id)?;
        if self.collision.set_shell(object, shell) { Ok(()) } else { Err(RigError::QueueFull("collision")) }
    }

    /// The collision pipeline's slot of watched object `id`.
    fn object_of(&self, id: u32) -> Result<ObjectId> {
        self.entries.iter().find(|e| e.id == id).map(|e| e.object).ok_or(RigError::UnknownObject(id))
    }

    /// Only checks objects whose bounds touch `region` (`None`: everywhere).
    pub(crate) fn set_region(&mut self, region: Option<collette::bounding_volume::Aabb>) -> Result<()> {
        if self.collision.set_region(region) { Ok(()) } else { Err(RigError::QueueFull("collision")) }
    }

    /// Pauses or resumes collision detection.
    pub(crate) fn pause(&mut self, paused: bool) -> Result<()> {
        if self.collision.pause(paused) { Ok(()) } else { Err(RigError::QueueFull("collision")) }
    }

    /// Frees what both threads handed back; returns how many objects (and surface grids) the force
    /// stage has returned since the last call.
    pub(crate) fn collect_garbage(&mut self) -> usize {
        self.free_returned();
        std::mem::take(&mut self.freed)
    }

    fn free_returned(&mut self) {
        self.collision.collect_retired();
        while self.garbage.pop().is_ok() {
            self.freed += 1;
        }
    }
}
