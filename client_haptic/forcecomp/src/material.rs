//! Per-object materials and the rigid-body motion the force laws need.
//!
//! You need this module to give an object its feel (stiffness, damping, friction, texture) and to describe how
//! the tool and the touched object move.

use glam::{Quat, Vec3};

use crate::error::{Result, non_negative};
use crate::texture::Texture;

/// How an object feels: the paper's ε_c and ε_d, plus friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Volumetric stiffness ε_c: force per overlap volume, N/m³ (default 3e6: 1 N at 0.33 cm³).
    pub stiffness_n_per_m3: f32,
    /// Damping ε_d on the relative normal velocity, N·s/m (default 2).
    pub damping_ns_per_m: f32,
    /// Coulomb friction coefficient (default 0.3).
    pub friction: f32,
    /// Ridges on the surface (default none: smooth).
    pub texture: Option<Texture>,
}

impl Default for Material {
    fn default() -> Self {
        Self { stiffness_n_per_m3: 3e6, damping_ns_per_m: 2.0, friction: 0.3, texture: None }
    }
}

impl Material {
    /// A frictionless material with the given stiffness and damping.
    pub const fn new(stiffness_n_per_m3: f32, damping_ns_per_m: f32) -> Self {
        Self { stiffness_n_per_m3, damping_ns_per_m, friction: 0.0, texture: None }
    }

    /// The material of a contact between two objects: stiffness and damping in series (two springs
    /// pressed together), friction the geometric mean, the texture `other`'s (the touched object's)
    /// or else this one's.
    pub fn combine(&self, other: &Material) -> Material {
        fn series(a: f32, b: f32) -> f32 {
            if a <= 0.0 || b <= 0.0 { 0.0 } else { a * b / (a + b) }
        }
        Material {
            stiffness_n_per_m3: series(self.stiffness_n_per_m3, other.stiffness_n_per_m3),
            damping_ns_per_m: series(self.damping_ns_per_m, other.damping_ns_per_m),
            friction: (self.friction.max(0.0) * other.friction.max(0.0)).sqrt(),
            texture: other.texture.or(self.texture),
        }
    }

    /// Checks that every value is finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        non_negative("stiffness_n_per_m3", self.stiffness_n_per_m3)?;
        non_negative("damping_ns_per_m", self.damping_ns_per_m)?;
        non_negative("friction", self.friction)?;
        self.texture.as_ref().map_or(Ok(()), Texture::validate)
    }
}

/// Where a rigid body is and how it moves right now, in world coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BodyMotion {
    /// Centre of mass, m.
    pub center_of_mass: Vec3,
    /// Orientation of the body's frame (its texture turns with it; default identity).
    pub orientation: Quat,
    /// Linear velocity of the centre of mass, m/s.
    pub linear_velocity: Vec3,
    /// Angular velocity, rad/s.
    pub angular_velocity: Vec3,
}

impl BodyMotion {
    /// A body at rest with its centre of mass at `center_of_mass`, unrotated.
    pub const fn at_rest(center_of_mass: Vec3) -> Self {
        Self { center_of_mass, orientation: Quat::IDENTITY, linear_velocity: Vec3::ZERO, angular_velocity: Vec3::ZERO }
    }

    /// Velocity of the body's material point at `point`, m/s.
    #[inline]
    pub fn velocity_at(&self, point: Vec3) -> Vec3 {
        self.linear_velocity + self.angular_velocity.cross(point - self.center_of_mass)
    }

    /// True when every value is finite.
    pub fn is_finite(&self) -> bool {
        self.center_of_mass.is_finite()
            && self.orientation.is_finite()
            && self.linear_velocity.is_finite()
            && self.angular_velocity.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_equal_materials_combine_to_half_the_stiffness() {
        let m = Material::default().combine(&Material::default());
        assert!((m.stiffness_n_per_m3 - 1.5e6).abs() < 1.0);
        assert!((m.friction - 0.3).abs() < 1e-6);
    }

    #[test]
    fn a_spinning_body_moves_its_points_tangentially() {
        let b = BodyMotion { angular_velocity: Vec3::Z, ..BodyMotion::at_rest(Vec3::ZERO) };
        assert!((b.velocity_at(Vec3::X) - Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn negative_or_nan_values_are_refused() {
        assert!(Material::new(-1.0, 0.0).validate().is_err());
        assert!(Material::new(1.0, f32::NAN).validate().is_err());
        assert!(Material::default().validate().is_ok());
    }
}
