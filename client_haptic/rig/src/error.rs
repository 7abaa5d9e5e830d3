//! Errors of the rig (start-up and control only; the threads' hot paths return none).

/// What can go wrong when starting or steering the rig.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The device layer refused.
    #[error(transparent)]
    Haptico(#[from] haptico::HapticoError),
    /// A force parameter is out of range.
    #[error(transparent)]
    ForceComp(#[from] forcecomp::ForceCompError),
    /// A command could not be queued: the thread is stopped or not keeping up.
    #[error("the {0} thread's command queue is full (is it running?)")]
    QueueFull(&'static str),
    /// No room for another object.
    #[error("at most {0} objects can be watched at once")]
    TooManyObjects(usize),
    /// No room for another watcher between two objects.
    #[error("at most {0} watchers between objects can run at once")]
    TooManyPairs(usize),
    /// A watcher between an object and itself.
    #[error("object {0} cannot be watched against itself")]
    SamePair(u32),
    /// A pose sample older than the object's newest, or not a number.
    #[error("object {id}'s pose at {t_us} µs is older than its newest or not finite")]
    BadSample {
        /// The object.
        id: u32,
        /// The sample's time, µs on the rig's clock.
        t_us: u64,
    },
    /// A pushed object's mass that is not a positive number.
    #[error("object {id}'s mass must be a positive number of kilograms, not {mass_kg}")]
    BadMass {
        /// The object.
        id: u32,
        /// The mass given, kg.
        mass_kg: f32,
    },
    /// No watched object has this id.
    #[error("no watched object has id {0}")]
    UnknownObject(u32),
    /// The operating system refused to start the collision thread.
    #[error("cannot start the collision thread: {0}")]
    Spawn(std::io::Error),
}

/// `Result` with [`RigError`].
pub type Result<T, E = RigError> = std::result::Result<T, E>;
