//! The collision pipeline (the paper's ColletteVolume with AddCollisionWatcher): a thread that owns the
//! loaded trees, reads the latest object poses lock-free, checks the watched pairs inside a region, and
//! publishes each pair's latest [`ContactSet`] lock-free.
//!
//! You need this module to run collision detection beside a 1 kHz haptic loop. Start it with
//! [`CollisionThread::spawn`]; add objects (you get a [`PoseWriter`] to move them from any thread) and
//! watchers (you get a [`ContactReader`] for the force thread); objects and watchers can be added and
//! removed while it runs. The thread never locks or allocates: commands and retired objects travel
//! through fixed-capacity ring buffers, poses and contacts through triple buffers. The core,
//! [`CollisionWorld`], takes the deadline as input and can be stepped by hand in tests.

mod thread;
mod world;

pub use thread::{CollisionHandle, CollisionThread, ContactReader, PoseWriter};
pub use world::{CollisionConfig, CollisionWorld, Command, ObjectId, Retired, TimedPose, WatcherId};

pub use haptic_common::ContactSet;
