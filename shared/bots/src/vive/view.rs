//! What the bot sees in one frame, put together from the replicated state and its memory.

use heist_shared::protocol::{CaseView, GuardView, ItemView, ViveAvatar};
use heist_shared::rules;

/// Everything the bot sees this frame.
pub(crate) struct View<'a> {
    pub(super) me: &'a ViveAvatar,
    pub(super) alarm: u8,
    pub(super) tuning: rules::GuardTuning,
    /// The guards: those in sight, and those out of sight where they are likely now.
    pub(super) guards: Vec<&'a GuardView>,
    pub(super) cases: Vec<&'a CaseView>,
    pub(super) items: Vec<&'a ItemView>,
    pub(super) secured: Vec<heist_shared::artifact::ArtifactKind>,
}
