//! Small stable identifiers used on the wire instead of ECS entities.

use serde::{Deserialize, Serialize};

/// The two roles of a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Role {
    /// The sighted thief (VR headset or desktop).
    Vive,
    /// The blind thief at the workbench (force-feedback device and audio).
    Phantom,
}

impl Role {
    /// The other role: the partner's.
    pub const fn partner(self) -> Role {
        match self {
            Role::Vive => Role::Phantom,
            Role::Phantom => Role::Vive,
        }
    }

    /// Byte stored in the connect token.
    pub const fn to_byte(self) -> u8 {
        match self {
            Role::Vive => 1,
            Role::Phantom => 2,
        }
    }

    /// Inverse of [`Role::to_byte`].
    pub const fn from_byte(b: u8) -> Option<Self> {
        match b {
            1 => Some(Role::Vive),
            2 => Some(Role::Phantom),
            _ => None,
        }
    }

    /// The role's name as typed on a command line and written in structured logs: `vive`, `phantom`.
    pub const fn name(self) -> &'static str {
        match self {
            Role::Vive => "vive",
            Role::Phantom => "phantom",
        }
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Role::Vive => "Vive",
            Role::Phantom => "Phantom",
        })
    }
}

impl std::str::FromStr for Role {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "vive" => Ok(Role::Vive),
            "phantom" => Ok(Role::Phantom),
            other => Err(format!("unknown role `{other}` (expected `vive` or `phantom`)")),
        }
    }
}

/// A guard, by its index in the level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct GuardId(pub u16);

/// A display case, by its index in the level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct CaseId(pub u16);

/// A pick-up-able item (an artifact copy or a prop). Numbered in a shuffled order so the number says
/// nothing about which copy is real.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct ItemId(pub u16);
