//! Surface texture: ridges felt under the tool, rendered as the force of a corrugated surface.
//!
//! You need this module to give a material a texture a player can feel and name ("ribbed"), rather
//! than only a friction coefficient. A [`Texture`] is a grating of grooves cut into the surface: its
//! height is `A·h` with `h = (cos(2π s / spacing) − 1) / 2` (0 on a ridge, −1 at the bottom of a
//! groove `A` deep), where `s` is the contact point's coordinate along the object's `axis`. Pressed
//! into by a depth `d`, such a surface pushes back with
//!
//! F = k · max(d + A·h, 0) · (n − A·∇ₜh),
//!
//! the gradient of the potential ½·k·max(d + A·h, 0)², so the ridges store and return energy but never
//! create it: a closed stroke over them does no net work (tested below). Any smooth rendering supplies
//! its normal force `f·n` and the texture replaces it ([`Texture::apply`]); the depth is `f / k`, so the
//! ridges feel the same on top of the volumetric force and under the 3-DOF proxy. The ridges reach up
//! to the smooth surface and no further, so where the smooth force is zero the texture's is too. The
//! force is bounded: at most `f·√(1 + (π·A/spacing)²)`.

use glam::{Quat, Vec3};

use crate::error::{Result, non_negative, positive};

/// A grating of ridges on a material's surface (object frame, object units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texture {
    /// Distance between two ridge crests along `axis`, object units (e.g. 0.003 m).
    pub spacing: f32,
    /// Depth of a groove below the ridges, object units (e.g. 0.0004 m).
    pub amplitude: f32,
    /// Direction along which the ridges repeat, object frame (normalised on use; default +Y: ridges
    /// that run round an upright object).
    pub axis: Vec3,
    /// Stiffness the ridges are pressed with, N per object unit of depth (N/m for an object in metres
    /// at scale 1): the smooth force's spring rate, which tells the depth from the force. The 3-DOF
    /// proxy uses its own spring instead.
    pub stiffness: f32,
}

impl Texture {
    /// Ridges `spacing` apart with grooves `amplitude` deep between them, repeating along +Y, pressed with `stiffness`.
    pub const fn ribs(spacing: f32, amplitude: f32, stiffness: f32) -> Self {
        Self { spacing, amplitude, axis: Vec3::Y, stiffness }
    }

    /// Checks every value (spacing and stiffness positive, amplitude non-negative, axis non-zero).
    pub fn validate(&self) -> Result<()> {
        positive("texture spacing", self.spacing)?;
        non_negative("texture amplitude", self.amplitude)?;
        positive("texture stiffness", self.stiffness)?;
        positive("texture axis length", self.axis.length())
    }

    /// Height of the surface at object-frame point `p`, in −1 (a groove's bottom) ..0 (a ridge), × `amplitude`.
    #[inline]
    pub fn height(&self, p: Vec3) -> f32 {
        0.5 * (self.phase(p).cos() - 1.0)
    }

    /// Ridges passed per second sliding at `speed` (object units per second) along the axis.
    pub fn ridges_per_s(&self, speed: f32) -> f32 {
        if self.spacing > 0.0 { speed.abs() / self.spacing } else { 0.0 }
    }

    fn phase(&self, p: Vec3) -> f32 {
        let axis = self.axis.normalize_or(Vec3::Y);
        std::f32::consts::TAU * p.dot(axis) / self.spacing
    }

    /// The force of the corrugated surface in place of a smooth normal force.
    ///
    /// `normal_force` is the smooth rendering's force along the surface normal (world frame, pointing
    /// out of the object, N); `point` is the contact point in the world frame and `object` the object's
    /// rotation and a point fixed in it (the ridges' phase is counted from there); `stiffness` the
    /// spring rate the depth is read with, N per world unit. Returns the replacement normal-plus-ridge
    /// force (world frame, N). A zero or non-finite input gives back `normal_force` unchanged.
    /// Allocation-free.
    #[inline]
    pub fn apply(&self, normal_force: Vec3, point: Vec3, object: (Quat, Vec3), stiffness: f32) -> Vec3 {
        let f = normal_force.length();
        if !(f > 0.0 && f.is_finite() && self.spacing > 0.0 && self.amplitude > 0.0 && point.is_finite()) {
            return normal_force;
        }
        let n = normal_force / f;
        let (rotation, translation) = object;
        let local = rotation.inverse() * (point - translation);
        let phase = self.phase(local);
        // k × depth: the smooth force's depth less the groove's depth at the contact.
        let pressed = (f + stiffness.max(0.0) * self.amplitude * 0.5 * (phase.cos() - 1.0)).max(0.0);
        // ∇h along the surface, world frame: −sin(phase)·π/spacing along the axis, normal part removed.
        let axis = rotation * self.axis.normalize_or(Vec3::Y);
        let gradient = axis * (-phase.sin() * std::f32::consts::PI / self.spacing);
        let tangential = gradient - n * gradient.dot(n);
        let out = (n - tangential * self.amplitude) * pressed;
        if out.is_finite() { out } else { normal_force }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: f32 = 800.0;
    const SPACING: f32 = 0.003;
    const AMPLITUDE: f32 = 0.0004;

    fn ribs() -> Texture {
        Texture::ribs(SPACING, AMPLITUDE, K)
    }

    /// The force on a point tool at `p` against the ribbed face x = 0 of an object filling x < 0
    /// (ridges along Y; the smooth force is k × depth).
    fn force_at(p: Vec3) -> Vec3 {
        let depth = (-p.x).max(0.0);
        let smooth = Vec3::X * (K * depth);
        ribs().apply(smooth, Vec3::new(0.0, p.y, p.z), (Quat::IDENTITY, Vec3::ZERO), K)
    }

    #[test]
    fn a_ridge_pushes_like_the_smooth_surface_and_a_groove_softer() {
        let depth = 0.001;
        let on_crest = ribs().apply(Vec3::X * (K * depth), Vec3::ZERO, (Quat::IDENTITY, Vec3::ZERO), K);
        let in_trough = ribs().apply(Vec3::X * (K * depth), Vec3::Y * (SPACING / 2.0), (Quat::IDENTITY, Vec3::ZERO), K);
        assert!((on_crest.x - K * depth).abs() < 1e-3, "{on_crest}");
        assert!((in_trough.x - K * (depth - AMPLITUDE)).abs() < 1e-3, "{in_trough}");
        // On a crest or in a trough the slope is flat: no push along the surface.
        assert!(on_crest.y.abs() < 1e-3 && in_trough.y.abs() < 1e-3);
    }

    #[test]
    fn on_a_flank_the_ridge_pushes_the_tool_down_its_slope() {
        // A quarter spacing past a ridge the surface falls towards +y: the tool is pushed to +y.
        let f = ribs().apply(Vec3::X * 0.8, Vec3::Y * (SPACING / 4.0), (Quat::IDENTITY, Vec3::ZERO), K);
        let (slope, pressed) = (std::f32::consts::PI * AMPLITUDE / SPACING, 0.8 - K * AMPLITUDE / 2.0);
        assert!((f.x - pressed).abs() < 1e-3 && (f.y - pressed * slope).abs() < 1e-3, "{f}, slope {slope}");
    }

    #[test]
    fn a_closed_stroke_over_the_ridges_does_no_net_work() {
        // In 1 mm, along 5 ridges, out, and back outside: the work done on the tool sums to zero.
        let corners = [
            Vec3::new(0.0005, 0.0, 0.0),
            Vec3::new(-0.001, 0.0, 0.0),
            Vec3::new(-0.001, 5.3 * SPACING, 0.0),
            Vec3::new(0.0005, 5.3 * SPACING, 0.0),
            Vec3::new(0.0005, 0.0, 0.0),
        ];
        let (mut work, mut gross) = (0.0f64, 0.0f64);
        for w in corners.windows(2) {
            let steps = 20_000;
            for i in 0..steps {
                let a = w[0].lerp(w[1], i as f32 / steps as f32);
                let b = w[0].lerp(w[1], (i + 1) as f32 / steps as f32);
                let dw = f64::from(force_at((a + b) / 2.0).dot(b - a));
                work += dw;
                gross += dw.abs();
            }
        }
        assert!(gross > 1e-4, "the stroke met the ridges: {gross} J");
        assert!(work.abs() < 1e-3 * gross, "net work {work} J of {gross} J moved");
    }

    #[test]
    fn the_force_is_bounded_and_never_pulls() {
        let slope = std::f32::consts::PI * AMPLITUDE / SPACING;
        for i in 0..1000 {
            let y = i as f32 * 1e-5;
            for depth in [0.0, 0.0001, 0.001, 0.004] {
                let f = force_at(Vec3::new(-depth, y, 0.0));
                let bound = K * depth * (1.0 + slope * slope).sqrt();
                assert!(f.length() <= bound + 1e-4, "{f} > {bound}");
                assert!(f.x >= 0.0, "pulls at depth {depth}, y {y}: {f}");
            }
        }
    }

    #[test]
    fn the_ridges_turn_and_move_with_the_object() {
        // The object turned a quarter round Z: its ridges now repeat along −X of the world, on a face
        // with normal +Y; the same local point gives the same height wherever the object is.
        let pose = (Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), Vec3::new(1.0, 2.0, 3.0));
        let local_trough = Vec3::Y * (SPACING / 2.0);
        let world = pose.0 * local_trough + pose.1;
        let f = ribs().apply(Vec3::Y * 0.8, world, pose, K);
        assert!((f.y - (0.8 - K * AMPLITUDE)).abs() < 1e-3, "{f}");
        assert!((ribs().height(local_trough) + 1.0).abs() < 1e-6);
    }

    #[test]
    fn no_force_or_a_broken_input_passes_through_unchanged() {
        let t = ribs();
        assert_eq!(t.apply(Vec3::ZERO, Vec3::ZERO, (Quat::IDENTITY, Vec3::ZERO), K), Vec3::ZERO);
        let f = Vec3::X;
        assert_eq!(t.apply(f, Vec3::NAN, (Quat::IDENTITY, Vec3::ZERO), K), f);
        assert!(Texture { spacing: 0.0, ..t }.validate().is_err());
        assert!(Texture { axis: Vec3::ZERO, ..t }.validate().is_err());
        assert!(t.validate().is_ok());
    }
}
