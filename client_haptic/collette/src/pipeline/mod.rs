//! The collision pipeline (the paper's ColletteVolume with AddCollisionWatcher): a thread that owns the
//! loaded trees, reads the latest object poses lock-free, checks the watched pairs inside a region, and
//! publishes each pair's latest result lock-free: a [`ContactSet`] of overlapping sphere pairs
//! (volumetric rendering) or the [`NearSpheres`] around a point tool's tip (3-DOF proxy rendering).
//!
//! You need this module to run collision detection beside a 1 kHz haptic loop. Start it with
//! [`CollisionThread::spawn`] (or [`CollisionThread::spawn_with`] and your own [`Pacer`]); add objects
//! (you get a [`PoseWriter`] to move them from any thread) and watchers (you get a reader for the force
//! thread); objects, trees and watchers can be added, replaced and removed while it runs, and it can be
//! paused. The thread never locks or allocates: commands and retired objects travel through
//! fixed-capacity ring buffers (the return ring sized so that it cannot fill), poses and results through
//! triple buffers, step timings through a bounded ring. An object the game moves can be given its last
//! poses with their times ([`PoseTrack`]): each step reads it at the step's time, so it moves smoothly
//! between the game's frames. Each step first finds the objects whose bounds overlap (sweep and prune),
//! so that watched pairs far apart cost no query. A scene watcher watches one object (the tool) against
//! every other in one buffer ([`SceneContacts`]); a summary watcher tells only whether and how much two
//! objects overlap ([`PairSummary`]). The core, [`CollisionWorld`], takes the deadline
//! as input; [`pipeline`] gives a [`CollisionStepper`] to step by hand in tests and lockstep runs.

mod broad;
mod scene;
mod thread;
mod track;
mod world;

pub use scene::{MAX_TOUCHED, PairSummary, SceneContacts, Touched};
pub use thread::{
    CollisionHandle, CollisionStepper, CollisionThread, ContactReader, FixedRate, NearReader, Pacer, PoseWriter,
    SceneReader, StepTiming, SummaryReader, WatcherReader, pipeline,
};
pub use track::{PoseTrack, TRACK_SAMPLES, TrackTiming, TrackedMotion};
pub use world::{
    CollisionConfig, CollisionWorld, Command, MAX_NEAR_SPHERES, NearSphere, NearSpheres, ObjectId, ObjectPose, Retired,
    StepReport, TimedPose, WatcherId, WatcherOutput,
};

pub use haptic_common::ContactSet;
