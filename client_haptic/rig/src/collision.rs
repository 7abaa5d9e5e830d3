//! The collision thread: at a fixed rate it takes the latest tool pose, runs collette's time-budgeted
//! overlap query against every watched object, publishes a [`CollisionFrame`] and broadcasts OnCollision.
//!
//! You need this module to run collision detection beside the haptic thread (paper Fig. 3). Objects and
//! the tool change through commands (boxed on the game thread); replaced ones come back to be freed
//! there, so the thread never allocates or frees in steady state.

use std::sync::Arc;
use std::time::{Duration, Instant};

use collette::query::{Budget, QueryWorkspace, overlap_budgeted, spheres_near};
use forcecomp::{Ball, BodyMotion};
use haptic_common::{Delegator, OnCollision};
use haptico::HapticClock;
use haptico::timing::{next_deadline, wait_until};

use crate::frame::{CollisionFrame, MAX_OBJECTS, ObjectSpec, ToolPoseMsg, ToolSpec};

/// Settings of the collision thread.
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionConfig {
    /// Step rate, Hz (default 1000).
    pub rate_hz: f32,
    /// Time a step's queries may take before the rest is estimated, µs (default 500).
    pub budget_us: u32,
    /// Spin instead of sleeping for the last part of each period, µs (default 300).
    pub spin_margin_us: u32,
    /// Capacity of the step-timing ring buffer (default 65 536).
    pub timing_capacity: usize,
    /// Periods a late loop may fall behind and still run every missed step (default 5).
    pub catch_up_periods: u32,
    /// Real-time FIFO priority, 1..=99 (default None); keep it below the haptic thread's.
    pub realtime_priority: Option<i32>,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            rate_hz: 1000.0,
            budget_us: 500,
            spin_margin_us: 300,
            timing_capacity: 1 << 16,
            catch_up_periods: 5,
            realtime_priority: None,
        }
    }
}

/// Timing and size of one collision step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTiming {
    /// Step counter.
    pub sequence: u64,
    /// Start on the haptic clock, µs.
    pub start_us: u64,
    /// Time since the previous step's start, µs.
    pub period_us: u32,
    /// Time spent querying, µs.
    pub work_us: u32,
    /// Contacts found.
    pub contacts: u32,
    /// True when a budget cut a query short.
    pub budget_hit: bool,
}

pub(crate) enum WorldCommand {
    SetTool(Box<ToolSpec>),
    AddObject(Box<WatchedObject>),
    RemoveObject(u32),
    Pause(bool),
    Stop,
}

#[allow(dead_code)] // held only to be dropped on the game thread
pub(crate) enum WorldGarbage {
    Tool(Box<ToolSpec>),
    Object(Box<WatchedObject>),
    Tree(Arc<collette::InnerSphereTree>),
}

/// A watched object with what is precomputed about it.
pub(crate) struct WatchedObject {
    pub(crate) spec: ObjectSpec,
    pub(crate) motion: BodyMotion,
}

impl WatchedObject {
    /// Boxes `spec` with its motion (allocates and walks the tree: call on the game thread).
    pub(crate) fn boxed(spec: ObjectSpec) -> Box<Self> {
        let motion = BodyMotion {
            orientation: spec.pose.rotation,
            ..BodyMotion::at_rest(spec.pose.transform_point(crate::frame::center_of_mass(&spec.tree)))
        };
        Box::new(Self { spec, motion })
    }
}

/// The collision thread's state.
pub(crate) struct CollisionWorld {
    pub(crate) tool: Box<ToolSpec>,
    // Boxed so that objects move in and out through the rings whole: unboxing here would free the box
    // on this thread.
    #[allow(clippy::vec_box)]
    pub(crate) objects: Vec<Box<WatchedObject>>,
    pub(crate) workspace: QueryWorkspace,
    pub(crate) poses: triple_buffer::Output<ToolPoseMsg>,
    pub(crate) frames: triple_buffer::Input<CollisionFrame>,
    pub(crate) commands: rtrb::Consumer<WorldCommand>,
    pub(crate) garbage: rtrb::Producer<WorldGarbage>,
    pub(crate) timings: rtrb::Producer<StepTiming>,
    pub(crate) on_collision: Delegator<OnCollision>,
    /// Proxy rendering: gather each object's spheres near the tip instead of overlapping the tool.
    pub(crate) proxy: bool,
    pub(crate) paused: bool,
    pub(crate) sequence: u64,
    pub(crate) last_start_us: Option<u64>,
}

impl CollisionWorld {
    fn discard(&mut self, g: WorldGarbage) {
        if let Err(rtrb::PushError::Full(g)) = self.garbage.push(g) {
            std::mem::forget(g); // leak rather than free on this thread
        }
    }

    /// Applies pending commands; returns false on Stop.
    pub(crate) fn apply_commands(&mut self) -> bool {
        for _ in 0..16 {
            let Ok(command) = self.commands.pop() else { break };
            match command {
                WorldCommand::Stop => return false,
                WorldCommand::Pause(p) => self.paused = p,
                WorldCommand::SetTool(tool) => {
                    let old = std::mem::replace(&mut self.tool, tool);
                    self.discard(WorldGarbage::Tool(old));
                }
                WorldCommand::AddObject(object) => {
                    if let Some(i) = self.objects.iter().position(|o| o.spec.id == object.spec.id) {
                        let old = std::mem::replace(&mut self.objects[i], object);
                        self.discard(WorldGarbage::Object(old));
                    } else if self.objects.len() < MAX_OBJECTS {
                        self.objects.push(object);
                    } else {
                        self.discard(WorldGarbage::Object(object));
                    }
                }
                WorldCommand::RemoveObject(id) => {
                    if let Some(i) = self.objects.iter().position(|o| o.spec.id == id) {
                        let old = self.objects.remove(i);
                        self.discard(WorldGarbage::Object(old));
                    }
                }
            }
        }
        true
    }

    /// One collision step for the latest tool pose, started at `start_us`, with queries cut at `deadline`.
    pub(crate) fn step(&mut self, clock: &HapticClock, start_us: u64, deadline: Option<Instant>) {
        if self.paused {
            return;
        }
        let pose = *self.poses.read();
        self.sequence += 1;
        let frame = self.frames.input_buffer_mut();
        frame.sequence = self.sequence;
        frame.pose_timestamp_us = pose.timestamp_us;
        frame.tool_pose = pose.pose;
        frame.tool_center_of_mass = self.tool.center_of_mass;
        frame.tool_material = self.tool.material;
        let mut count = 0;
        let mut contacts = 0u32;
        let mut budget_hit = false;
        frame.balls.clear();
        let proxy = self.proxy;
        for object in self.objects.iter().filter(|_| proxy) {
            let spec = &object.spec;
            let first = frame.balls.len();
            // Too many spheres within reach (a fine packing): gather again nearer the tip, so that the
            // nearest are never the ones left out.
            let mut reach = pose.reach;
            for _ in 0..4 {
                frame.balls.truncate(first);
                let balls = &mut frame.balls;
                spheres_near(
                    &spec.tree,
                    &spec.pose,
                    pose.pose.translation,
                    reach,
                    &mut self.workspace,
                    |center, radius| balls.push(Ball { center, radius }, count),
                );
                if frame.balls.overflow == 0 {
                    break;
                }
                reach *= 0.6;
            }
            if frame.balls.len() == first {
                continue;
            }
            let slot = &mut frame.objects[count];
            slot.object_id = spec.id;
            slot.material = spec.material;
            slot.motion = object.motion;
            slot.contacts.clear();
            count += 1;
        }
        contacts += frame.balls.len() as u32;
        for object in self.objects.iter().filter(|_| !proxy) {
            let slot = &mut frame.objects[count];
            let budget = deadline.map_or(Budget::Unlimited, Budget::Deadline);
            let spec = &object.spec;
            let result = overlap_budgeted(
                &self.tool.tree,
                &pose.pose,
                &spec.tree,
                &spec.pose,
                budget,
                &mut self.workspace,
                &mut slot.contacts,
            );
            budget_hit |= !result.complete;
            if slot.contacts.is_empty() {
                continue;
            }
            slot.object_id = spec.id;
            slot.material = spec.material;
            slot.motion = object.motion;
            slot.contacts.object_a = 0;
            slot.contacts.object_b = spec.id;
            slot.contacts.sequence = self.sequence;
            slot.contacts.timestamp_us = pose.timestamp_us;
            contacts += slot.contacts.len() as u32;
            self.on_collision.broadcast(&slot.contacts);
            count += 1;
        }
        frame.count = count;
        let end_us = clock.now_us().max(start_us);
        frame.step_us = (end_us - start_us) as u32;
        self.frames.publish();
        let period_us = self.last_start_us.map_or(0, |s| start_us.saturating_sub(s)) as u32;
        self.last_start_us = Some(start_us);
        let _ = self.timings.push(StepTiming {
            sequence: self.sequence,
            start_us,
            period_us,
            work_us: (end_us - start_us) as u32,
            contacts,
            budget_hit,
        });
    }

    /// Runs the fixed-rate loop until Stop.
    pub(crate) fn run(mut self, clock: HapticClock, config: CollisionConfig) -> Self {
        if let Some(priority) = config.realtime_priority {
            haptico::timing::make_current_thread_realtime(priority);
        }
        let period_ns = (1e9 / config.rate_hz.max(1.0) as f64) as u64;
        let spin_ns = config.spin_margin_us as u64 * 1000;
        let mut deadline = clock.now_ns() + period_ns;
        loop {
            wait_until(&clock, deadline, spin_ns);
            if !self.apply_commands() {
                break;
            }
            let start = Instant::now();
            let start_us = clock.now_us();
            self.step(&clock, start_us, Some(start + Duration::from_micros(config.budget_us as u64)));
            let (next, _) = next_deadline(deadline, clock.now_ns(), period_ns, config.catch_up_periods as u64);
            deadline = next;
        }
        self
    }
}
