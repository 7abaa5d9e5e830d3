//! What an artifact is and what touch can tell about one copy: kinds, materials, traits, and the
//! shared look that is all the sighted side ever sees.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A kind of target artifact. Every copy of a kind looks the same; copies differ only in [`CopyTraits`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ArtifactKind {
    /// A golden crown; its copies differ in the number of points on the rim.
    Crown,
    /// A clay amphora; its copies differ in the number of vertical ridges on the belly.
    Amphora,
    /// A squat stone idol; its copies differ in the number of notches cut into its body.
    Idol,
}

impl ArtifactKind {
    /// Every kind, in a fixed order.
    pub const ALL: [ArtifactKind; 3] = [ArtifactKind::Crown, ArtifactKind::Amphora, ArtifactKind::Idol];

    /// Lower-case display name, as spoken ("crown").
    pub fn name(self) -> &'static str {
        match self {
            ArtifactKind::Crown => "crown",
            ArtifactKind::Amphora => "amphora",
            ArtifactKind::Idol => "idol",
        }
    }

    /// The shape feature that is counted, singular and plural ("point", "points").
    pub fn feature_noun(self) -> (&'static str, &'static str) {
        match self {
            ArtifactKind::Crown => ("point", "points"),
            ArtifactKind::Amphora => ("ridge", "ridges"),
            ArtifactKind::Idol => ("notch", "notches"),
        }
    }

    /// Inclusive range of feature counts that copies of this kind are generated with.
    pub fn feature_range(self) -> std::ops::RangeInclusive<u32> {
        match self {
            ArtifactKind::Crown => 5..=9,
            ArtifactKind::Amphora => 4..=9,
            ArtifactKind::Idol => 2..=6,
        }
    }
}

impl fmt::Display for ArtifactKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a surface responds to the haptic tool; the values a force renderer consumes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Contact stiffness, N/m (consumer devices render about 200–1000 N/m).
    pub stiffness_n_per_m: f32,
    /// Contact damping, N·s/m.
    pub damping: f32,
    /// Coulomb friction coefficient, dimensionless (0 = ice, ~0.6 = rough stone).
    pub friction: f32,
    /// Ridges running round the copy (None: a smooth surface).
    pub ridges: Option<Ridges>,
}

/// Ridges running round an upright copy, repeating up its height: what makes a copy feel ribbed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ridges {
    /// Distance from one ridge to the next, m.
    pub spacing_m: f32,
    /// Depth of the grooves between them, m.
    pub depth_m: f32,
}

impl Ridges {
    /// The ridges of every rough copy: 3 mm apart, grooves 0.3 mm deep (fluted stone, combed clay;
    /// a stylus tip feels them one by one at a stroke of a few centimetres a second).
    pub const ROUGH: Ridges = Ridges { spacing_m: 0.003, depth_m: 0.0003 };
}

/// A material as a player can name it by touch: hard or soft, smooth or rough.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum MaterialClass {
    /// Hard and smooth, like polished gold.
    HardSmooth,
    /// Hard and ribbed, like fluted stone (ridges 3 mm apart, more friction).
    HardRough,
    /// Soft and smooth, like waxed leather.
    SoftSmooth,
    /// Soft and ribbed, like combed clay (ridges 3 mm apart, more friction).
    SoftRough,
}

impl MaterialClass {
    /// Every class, in a fixed order.
    pub const ALL: [MaterialClass; 4] =
        [MaterialClass::HardSmooth, MaterialClass::HardRough, MaterialClass::SoftSmooth, MaterialClass::SoftRough];

    /// Concrete contact parameters for this class, within what a consumer device can render.
    pub fn material(self) -> Material {
        // Hard reads as hard from about 0.8 N/mm on a desktop device; 0.3 N/mm is clearly soft.
        let (stiffness_n_per_m, damping) = if self.is_hard() { (800.0, 1.0) } else { (300.0, 1.5) };
        let (friction, ridges) = if self.is_rough() { (0.6, Some(Ridges::ROUGH)) } else { (0.1, None) };
        Material { stiffness_n_per_m, damping, friction, ridges }
    }

    /// True for the hard classes.
    pub fn is_hard(self) -> bool {
        matches!(self, MaterialClass::HardSmooth | MaterialClass::HardRough)
    }

    /// True for the rough classes (ribbed, with more friction).
    pub fn is_rough(self) -> bool {
        matches!(self, MaterialClass::HardRough | MaterialClass::SoftRough)
    }

    /// Spoken adjectives ("hard and smooth", "soft and ribbed").
    pub fn adjective(self) -> &'static str {
        match self {
            MaterialClass::HardSmooth => "hard and smooth",
            MaterialClass::HardRough => "hard and ribbed",
            MaterialClass::SoftSmooth => "soft and smooth",
            MaterialClass::SoftRough => "soft and ribbed",
        }
    }

    /// A spoken comparison that follows the adjectives ("like polished gold").
    pub fn simile(self) -> &'static str {
        match self {
            MaterialClass::HardSmooth => "like polished gold",
            MaterialClass::HardRough => "like fluted stone",
            MaterialClass::SoftSmooth => "like waxed leather",
            MaterialClass::SoftRough => "like combed clay",
        }
    }

    /// The class whose [`material`](Self::material) is nearest to `m`.
    ///
    /// Distances scale stiffness by 1000 N/m, friction by 0.5 and damping by 5 N·s/m; ridges where
    /// the class has none (or none where it has them) count as far as the friction's whole range.
    pub fn nearest(m: &Material) -> MaterialClass {
        let distance = |c: MaterialClass| {
            let r = c.material();
            let ds = (m.stiffness_n_per_m - r.stiffness_n_per_m) / 1000.0;
            let df = (m.friction - r.friction) / 0.5;
            let dd = (m.damping - r.damping) / 5.0;
            let dr = if m.ridges.is_some() == r.ridges.is_some() { 0.0 } else { 1.0 };
            let d = ds * ds + df * df + dd * dd + dr;
            if d.is_nan() { f32::INFINITY } else { d }
        };
        let mut best = MaterialClass::ALL[0];
        for c in MaterialClass::ALL {
            if distance(c) < distance(best) {
                best = c;
            }
        }
        best
    }
}

/// Everything touch can tell about one copy; the server keeps these, clients never get them as data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct CopyTraits {
    /// Which artifact this is a copy of.
    pub kind: ArtifactKind,
    /// How many points / ridges / notches the copy has.
    pub feature_count: u32,
    /// What the copy is made of.
    pub material: MaterialClass,
}

/// The visual description shared by every copy of a kind; carries no trait by construction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArtifactLook {
    /// Base colour, sRGB 0–255.
    pub colour_srgb: [u8; 3],
    /// Nominal size: diameter along x, height along y, diameter along z, metres.
    pub size_m: [f32; 3],
    /// Index of the visual mesh in the VR client's catalogue (0 crown, 1 amphora, 2 idol).
    pub style_id: u16,
}

/// The look shared by all copies of `kind`.
pub fn look(kind: ArtifactKind) -> ArtifactLook {
    match kind {
        ArtifactKind::Crown => ArtifactLook { colour_srgb: [212, 175, 55], size_m: [0.10, 0.07, 0.10], style_id: 0 },
        ArtifactKind::Amphora => ArtifactLook { colour_srgb: [176, 96, 52], size_m: [0.10, 0.12, 0.10], style_id: 1 },
        ArtifactKind::Idol => ArtifactLook { colour_srgb: [120, 128, 110], size_m: [0.086, 0.11, 0.086], style_id: 2 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_material_is_renderable_on_a_consumer_device() {
        for c in MaterialClass::ALL {
            let m = c.material();
            assert!((200.0..=1000.0).contains(&m.stiffness_n_per_m), "{c:?}");
            assert!(m.damping > 0.0 && (0.0..=1.0).contains(&m.friction), "{c:?}");
        }
    }

    #[test]
    fn nearest_class_of_a_class_material_is_that_class() {
        for c in MaterialClass::ALL {
            assert_eq!(MaterialClass::nearest(&c.material()), c);
        }
    }

    #[test]
    fn nearest_class_tolerates_perturbed_values() {
        let m = Material { stiffness_n_per_m: 700.0, damping: 1.2, friction: 0.5, ridges: Some(Ridges::ROUGH) };
        assert_eq!(MaterialClass::nearest(&m), MaterialClass::HardRough);
    }

    #[test]
    fn look_is_the_same_for_every_call_and_distinct_per_kind() {
        for k in ArtifactKind::ALL {
            assert_eq!(look(k), look(k));
        }
        assert_ne!(look(ArtifactKind::Crown).style_id, look(ArtifactKind::Idol).style_id);
    }
}
