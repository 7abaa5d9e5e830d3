//! The 3-DOF god-object (proxy) force for point tools on an Inner Sphere Tree's spheres.
//!
//! You need this module for 3-DOF devices (Touch, Omni, Falcon, Inverse3: a stylus tip, force only).
//! The object is given as its inner spheres near the tip ([`Ball`]s, from the collision thread). The
//! tip is a small ball of radius `tip_radius`; the surface it is held on is where the tip's overlap with
//! the inner spheres is a small fixed volume (a cap [`SURFACE_CAP`] × `tip_radius` high). That surface
//! is smooth (the lens volume is C¹ in the tip's position, as in the volumetric force), so the proxy
//! slides over an inner-sphere packing without catching in the gaps between spheres, as a point on the
//! union of the spheres would.
//!
//! An object can also be given as a field instead of balls ([`TipField`]): the overlap of the tip with
//! it and its gradient, such as [`half_space_overlap`] at the signed distance a surface grid gives. The
//! tip is then held on the object's true surface, whose normals change smoothly, not on its packing;
//! both kinds add up, so a tip between a grid-backed object and a packed one is held off both.
//!
//! Each tick the proxy slides along that surface towards the device point (tangential steps, each
//! followed by a Newton step back onto the surface); friction keeps it in place while the pull along the
//! surface stays inside the friction cone. A spring from the device to the proxy is the force, so the
//! force grows with the penetration and points out of the object; the proxy leaves the surface only
//! when the way back to the device is free, so a thin part cannot be pushed through.

use std::f32::consts::PI;

use glam::Vec3;

use crate::error::{Result, non_negative, positive};

/// A sphere of the object, in the frame the device point is given in.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ball {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

/// Parameters of the proxy force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyConfig {
    /// Spring between proxy and device, N/m (default 300); clamp it to the device's stiffness limit.
    pub stiffness_n_per_m: f32,
    /// Damping of the device's speed into the surface, N·s/m (default 0.5).
    pub damping_ns_per_m: f32,
    /// Coulomb friction coefficient (default 0.3).
    pub friction: f32,
    /// Radius of the tip ball, in the balls' units (default 0.002); make it at least the spacing of
    /// the inner spheres near the surface, so that the surface it feels is smooth.
    pub tip_radius: f32,
}

impl Default for ProxyConfig {
    fn default() -> Self {
        Self { stiffness_n_per_m: 300.0, damping_ns_per_m: 0.5, friction: 0.3, tip_radius: 0.002 }
    }
}

impl ProxyConfig {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        positive("stiffness_n_per_m", self.stiffness_n_per_m)?;
        non_negative("damping_ns_per_m", self.damping_ns_per_m)?;
        non_negative("friction", self.friction)?;
        positive("tip_radius", self.tip_radius)
    }
}

/// More of what the tip is held outside of, besides the balls: for each object given as a field, the
/// tip's overlap volume with it at the tip's centre `p` and that volume's gradient (pointing into the
/// object), in the balls' units. Called many times a tick, on the haptic thread: no allocation.
pub trait TipField {
    /// The tip's (radius `tip_radius`) overlap volume at `p` and its gradient.
    fn overlap_and_gradient(&self, p: Vec3, tip_radius: f32) -> (f32, Vec3);
}

/// No field: the balls alone.
impl TipField for () {
    fn overlap_and_gradient(&self, _: Vec3, _: f32) -> (f32, Vec3) {
        (0.0, Vec3::ZERO)
    }
}

/// The tip's overlap with the object behind a surface, taken as flat at the tip: the cap the tangent
/// plane cuts from the tip when its centre is `depth` inside the surface (negative: outside), and the
/// gradient of that volume along `inward` (the unit normal into the object; the distance's gradient).
/// Exact for a flat face, C¹ in the depth, and the same volume the balls give for the same place, so
/// the tip rests `(1 − SURFACE_CAP) × tip_radius` outside the surface either way.
pub fn half_space_overlap(tip_radius: f32, depth: f32, inward: Vec3) -> (f32, Vec3) {
    let h = (tip_radius + depth).clamp(0.0, 2.0 * tip_radius);
    if !(h.is_finite() && inward.is_finite()) {
        return (0.0, Vec3::ZERO);
    }
    (cap_volume(tip_radius, h), inward * (PI * h * (2.0 * tip_radius - h)))
}

/// The surface is where the tip overlaps the object by a cap this high, as a fraction of its radius.
pub const SURFACE_CAP: f32 = 0.2;
/// Tangential steps per update, each at most half the tip's radius (so the proxy follows the device at
/// up to 4 tip radii per tick) and followed by Newton steps back onto the surface.
const SLIDE_STEPS: usize = 8;
/// Points checked on the way from the proxy back to the device before it lets go of the surface.
const RELEASE_SAMPLES: usize = 8;

/// The proxy's state.
#[derive(Clone, Debug, Default)]
pub struct GodObject {
    /// Where the proxy was last tick (`None` before the first update).
    last: Option<Vec3>,
    in_contact: bool,
    normal: Vec3,
}

impl GodObject {
    /// A proxy not yet in contact (it starts on the device).
    pub fn new() -> Self {
        Self::default()
    }

    /// The proxy position (the device point while free).
    pub fn proxy(&self) -> Vec3 {
        self.last.unwrap_or(Vec3::ZERO)
    }

    /// The surface's outward normal at the proxy while in contact (zero while free).
    pub fn normal(&self) -> Vec3 {
        if self.in_contact { self.normal } else { Vec3::ZERO }
    }

    /// True while the proxy is held on a surface.
    pub fn in_contact(&self) -> bool {
        self.in_contact
    }

    /// Moves the proxy for the device point `device` against `balls` (both in the balls' frame) and
    /// returns the force on the device along that frame's axes, N: k × (proxy − device) / `scale`, where
    /// `scale` is how many of the balls' units make one metre at the device, plus damping of the device's
    /// `velocity` (m/s, along the same axes) into the surface. Allocation-free; non-finite or empty balls
    /// are ignored.
    pub fn update(&mut self, config: &ProxyConfig, device: Vec3, velocity: Vec3, balls: &[Ball], scale: f32) -> Vec3 {
        self.update_with(config, device, velocity, balls, &(), scale)
    }

    /// [`update`](Self::update) against `balls` and the objects given as `field` together.
    pub fn update_with<F: TipField + ?Sized>(
        &mut self,
        config: &ProxyConfig,
        device: Vec3,
        velocity: Vec3,
        balls: &[Ball],
        field: &F,
        scale: f32,
    ) -> Vec3 {
        if !device.is_finite() || config.tip_radius.is_nan() || config.tip_radius <= 0.0 {
            return Vec3::ZERO;
        }
        let surface = Surface {
            balls,
            field,
            tip: config.tip_radius,
            level: cap_volume(config.tip_radius, SURFACE_CAP * config.tip_radius),
        };
        let last = self.last.filter(|p| p.is_finite()).unwrap_or(device);
        let start = if self.in_contact {
            if surface.volume(device) <= surface.level && surface.way_is_free(last, device) {
                return self.release(device);
            }
            surface.project(last)
        } else {
            if surface.volume(device) <= surface.level {
                return self.release(device);
            }
            // Coming from free space: the proxy meets the surface where the path from last tick's
            // position (outside) entered it.
            surface.entry(last, device)
        };
        let free = surface.slide(start, device);
        let mut proxy = free;
        if self.in_contact {
            // Friction: stay put while the slide is inside the cone mu × penetration; else slide by
            // what exceeds it.
            let penetration = (free - device).length();
            let slide = free - start;
            let (len, cone) = (slide.length(), config.friction * penetration);
            proxy = if len <= cone { start } else { surface.slide(start, start + slide * ((len - cone) / len)) };
        }
        self.last = Some(proxy);
        self.in_contact = true;
        self.normal = -surface.volume_and_gradient(proxy).1.normalize_or_zero();
        let spring = (proxy - device) * (config.stiffness_n_per_m / scale.max(f32::MIN_POSITIVE));
        let n = spring.normalize_or_zero();
        let into = velocity.dot(n).min(0.0); // damp only motion into the surface
        let force = spring - config.damping_ns_per_m * into * n;
        if force.is_finite() { force } else { Vec3::ZERO }
    }

    fn release(&mut self, device: Vec3) -> Vec3 {
        self.last = Some(device);
        self.in_contact = false;
        Vec3::ZERO
    }
}

/// The surface the tip is held on: where its overlap volume with the balls and the field is `level`.
struct Surface<'a, F: TipField + ?Sized> {
    balls: &'a [Ball],
    field: &'a F,
    tip: f32,
    level: f32,
}

impl<F: TipField + ?Sized> Surface<'_, F> {
    fn valid(&self) -> impl Iterator<Item = &Ball> {
        self.balls.iter().filter(|b| b.center.is_finite() && b.radius.is_finite() && b.radius > 0.0)
    }

    /// The tip's overlap volume with the balls at `p`.
    fn volume(&self, p: Vec3) -> f32 {
        let field = self.field.overlap_and_gradient(p, self.tip).0;
        field + self.valid().map(|b| lens_volume(self.tip, b.radius, p.distance(b.center))).sum::<f32>()
    }

    /// The overlap volume at `p` and its gradient (pointing into the object).
    fn volume_and_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let (mut v, mut g) = self.field.overlap_and_gradient(p, self.tip);
        for b in self.valid() {
            let delta = p - b.center;
            let d = delta.length();
            v += lens_volume(self.tip, b.radius, d);
            if d > 1e-12 {
                g -= delta / d * (PI * lens_circle_sq(self.tip, b.radius, d));
            }
        }
        (v, g)
    }

    /// `p` moved onto the surface along the gradient (up to five Newton steps of at most half the tip's
    /// radius, until the volume is within 0.1 % of the level; unchanged where it has no gradient).
    fn project(&self, mut p: Vec3) -> Vec3 {
        for _ in 0..5 {
            let (v, g) = self.volume_and_gradient(p);
            let gg = g.length_squared();
            if !(gg > 0.0 && v.is_finite()) || (v - self.level).abs() <= 1e-3 * self.level {
                break;
            }
            p -= (g * ((v - self.level) / gg)).clamp_length_max(0.5 * self.tip);
        }
        p
    }

    /// True when `p` is on the surface (within 5 % of the level).
    fn on_surface(&self, p: Vec3) -> bool {
        (self.volume(p) - self.level).abs() <= 0.05 * self.level
    }

    /// Slides from `from` (on the surface) towards `goal` along the surface: the tangential part of
    /// the way (at most half the tip's radius at a time), then back onto the surface, a few times;
    /// a step that does not come back onto the surface (a crease) is not taken. Ends at the surface
    /// point nearest `goal` around `from`.
    fn slide(&self, from: Vec3, goal: Vec3) -> Vec3 {
        let mut p = from;
        for _ in 0..SLIDE_STEPS {
            let (_, g) = self.volume_and_gradient(p);
            let Some(n) = (-g).try_normalize() else { break };
            let way = goal - p;
            let mut step = (way - way.dot(n) * n).clamp_length_max(0.5 * self.tip);
            // Over a crease the Newton steps may not come back onto the surface: try shorter steps.
            let mut next = None;
            for _ in 0..4 {
                if step.length_squared() < (1e-4 * self.tip).powi(2) {
                    break;
                }
                let candidate = self.project(p + step);
                if self.on_surface(candidate) {
                    next = Some(candidate);
                    break;
                }
                step *= 0.5;
            }
            match next {
                Some(q) => p = q,
                None => break,
            }
        }
        p
    }

    /// Where the way from `outside` (under the level) to `inside` (over it) crosses the surface
    /// (bisection).
    fn entry(&self, outside: Vec3, inside: Vec3) -> Vec3 {
        if self.volume(outside) > self.level {
            return self.project(outside);
        }
        let (mut a, mut b) = (outside, inside);
        for _ in 0..20 {
            let m = (a + b) * 0.5;
            if self.volume(m) > self.level { b = m } else { a = m }
        }
        a
    }

    /// True when no point on the way from `from` to `to` is inside the surface.
    fn way_is_free(&self, from: Vec3, to: Vec3) -> bool {
        (1..RELEASE_SAMPLES).all(|i| self.volume(from.lerp(to, i as f32 / RELEASE_SAMPLES as f32)) <= self.level)
    }
}

/// Volume of a cap of height `h` cut from a ball of radius `r`.
fn cap_volume(r: f32, h: f32) -> f32 {
    PI * h * h * (3.0 * r - h) / 3.0
}

/// Overlap volume of balls of radii `r1` and `r2` whose centres are `d` apart.
fn lens_volume(r1: f32, r2: f32, d: f32) -> f32 {
    let s = r1 + r2;
    if d >= s {
        return 0.0;
    }
    let diff = (r1 - r2).abs();
    if d <= diff {
        let r = r1.min(r2);
        return 4.0 / 3.0 * PI * r * r * r;
    }
    let t = s - d;
    (PI * t * t * (d * d + 2.0 * d * s - 3.0 * diff * diff) / (12.0 * d)).max(0.0)
}

/// Squared radius of the circle where the two balls' surfaces meet (minus the derivative of the lens
/// volume over the centre distance, divided by π); 0 when apart or nested.
fn lens_circle_sq(r1: f32, r2: f32, d: f32) -> f32 {
    if d >= r1 + r2 || d <= (r1 - r2).abs() {
        return 0.0;
    }
    ((-d + r1 + r2) * (d - r1 + r2) * (d + r1 - r2) * (d + r1 + r2) / (4.0 * d * d)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f32 = 0.002;
    const K: ProxyConfig =
        ProxyConfig { stiffness_n_per_m: 500.0, damping_ns_per_m: 0.0, friction: 0.0, tip_radius: R };
    /// Where the tip's centre rests above a flat face: the cap it overlaps is SURFACE_CAP × R high.
    const REST: f32 = R * (1.0 - SURFACE_CAP);

    /// A flat floor at y = 0 (a 10 m ball: its curvature is 5 µm over a centimetre).
    fn floor() -> Vec<Ball> {
        vec![Ball { center: Vec3::new(0.0, -10.0, 0.0), radius: 10.0 }]
    }

    fn touch(g: &mut GodObject, config: &ProxyConfig, balls: &[Ball], at: Vec3) -> Vec3 {
        g.update(config, at + Vec3::Y * 0.01, Vec3::ZERO, balls, 1.0);
        g.update(config, at, Vec3::ZERO, balls, 1.0)
    }

    #[test]
    fn a_tip_pressed_into_a_floor_is_pushed_up_by_the_stiffness_times_the_depth() {
        let (mut g, balls) = (GodObject::new(), floor());
        assert_eq!(g.update(&K, Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &balls, 1.0), Vec3::ZERO);
        let f = g.update(&K, Vec3::new(0.0, REST - 0.002, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!((f - Vec3::new(0.0, 1.0, 0.0)).length() < 0.02, "{f}");
        assert!((g.proxy().y - REST).abs() < 2e-5 && g.in_contact(), "{}", g.proxy());
        assert!((g.normal() - Vec3::Y).length() < 1e-3, "the floor's normal: {}", g.normal());
        // Deeper: more force, never a pop-through.
        let f = g.update(&K, Vec3::new(0.0, -0.5, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!((f.y - 500.0 * (0.5 + REST)).abs() < 0.5, "{f}");
        // Back out: no force.
        assert_eq!(g.update(&K, Vec3::new(0.0, REST + 0.001, 0.0), Vec3::ZERO, &balls, 1.0), Vec3::ZERO);
        assert!(!g.in_contact() && g.normal() == Vec3::ZERO);
    }

    #[test]
    fn the_force_is_in_newtons_per_metre_at_the_device_when_the_scene_is_scaled() {
        let (mut g, balls) = (GodObject::new(), floor());
        g.update(&K, Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &balls, 2.0);
        // 2 mm deep in the balls' frame is 1 mm at the device.
        let f = g.update(&K, Vec3::new(0.0, REST - 0.002, 0.0), Vec3::ZERO, &balls, 2.0);
        assert!((f.y - 0.5).abs() < 0.01, "{f}");
    }

    #[test]
    fn without_friction_it_slides_and_with_friction_it_holds_until_the_cone_is_left() {
        let balls = floor();
        let deep = REST - 0.002;
        let mut g = GodObject::new();
        touch(&mut g, &K, &balls, Vec3::new(0.0, deep, 0.0));
        let f = g.update(&K, Vec3::new(0.005, deep, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!(f.x.abs() < 0.01 && (g.proxy().x - 0.005).abs() < 1e-4, "slid along: {f} {}", g.proxy());

        let sticky = ProxyConfig { friction: 0.5, ..K };
        let mut g = GodObject::new();
        touch(&mut g, &sticky, &balls, Vec3::new(0.0, deep, 0.0));
        // 0.5 mm sideways at 2 mm deep is inside the cone (0.5 × 2 mm = 1 mm): held, pulled back.
        let f = g.update(&sticky, Vec3::new(0.0005, deep, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!(g.proxy().x.abs() < 1e-5 && f.x < -0.2, "held: {f} {}", g.proxy());
        // 3 mm sideways leaves it: the proxy slides to the cone's edge, the drag is mu times the push.
        let f = g.update(&sticky, Vec3::new(0.003, deep, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!((g.proxy().x - 0.002).abs() < 1e-4, "slid to the cone's edge: {}", g.proxy());
        assert!((-f.x / f.y - 0.5).abs() < 0.03, "drag over push = mu: {f}");
    }

    #[test]
    fn an_inside_corner_pushes_out_along_both_walls() {
        let mut balls = floor();
        balls.push(Ball { center: Vec3::new(-10.0, 0.0, 0.0), radius: 10.0 });
        let mut g = GodObject::new();
        g.update(&K, Vec3::new(0.01, 0.01, 0.0), Vec3::ZERO, &balls, 1.0);
        let f = g.update(&K, Vec3::new(-0.001, -0.001, 0.0), Vec3::ZERO, &balls, 1.0);
        assert!(f.x > 0.5 && f.y > 0.5, "{f}");
        assert!(g.proxy().x > 0.0 && g.proxy().y > 0.0, "{}", g.proxy());
    }

    #[test]
    fn a_thin_plate_is_not_pushed_through() {
        // A plate 2 mm thick: small balls in a row at y = 0.
        let balls: Vec<Ball> =
            (-40..=40).map(|i| Ball { center: Vec3::new(i as f32 * 5e-4, 0.0, 0.0), radius: 1e-3 }).collect();
        let mut g = GodObject::new();
        g.update(&K, Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &balls, 1.0);
        for y in [0.002, 0.0, -0.002, -0.004, -0.008] {
            let f = g.update(&K, Vec3::new(0.0, y, 0.0), Vec3::ZERO, &balls, 1.0);
            assert!(f.y > 0.0 && g.proxy().y > 0.001, "at {y}: {f}, proxy {}", g.proxy());
        }
    }

    #[test]
    fn a_point_slips_between_two_balls_and_a_wider_tip_glides_over_the_gap() {
        // Two 1 cm balls whose surfaces leave a 1 mm gap at x = 0.
        let balls = [
            Ball { center: Vec3::new(-0.0105, -0.01, 0.0), radius: 0.01 },
            Ball { center: Vec3::new(0.0105, -0.01, 0.0), radius: 0.01 },
        ];
        let point = ProxyConfig { tip_radius: 1e-4, ..K };
        let mut g = GodObject::new();
        assert_eq!(touch(&mut g, &point, &balls, Vec3::new(0.0, -0.009, 0.0)), Vec3::ZERO);
        let tip = ProxyConfig { tip_radius: 0.001, ..K };
        let mut g = GodObject::new();
        let f = touch(&mut g, &tip, &balls, Vec3::new(0.0, -0.009, 0.0));
        assert!(f.y > 0.5 && g.proxy().y > -0.008, "held above the gap: {f}, proxy {}", g.proxy());
        // And slides across it without catching: the force stays upright on the way.
        for i in 1..=20 {
            let x = i as f32 * 1e-4 - 0.001;
            let f = g.update(&tip, Vec3::new(x, -0.009, 0.0), Vec3::ZERO, &balls, 1.0);
            assert!(f.y > 0.5 && f.x.abs() < f.y, "at {x}: {f}");
        }
    }

    #[test]
    fn damping_resists_only_motion_into_the_surface() {
        let balls = floor();
        let damped = ProxyConfig { damping_ns_per_m: 2.0, ..K };
        let deep = Vec3::new(0.0, REST - 0.002, 0.0);
        let mut g = GodObject::new();
        touch(&mut g, &damped, &balls, deep);
        let pressing = g.update(&damped, deep, Vec3::new(0.0, -0.1, 0.0), &balls, 1.0);
        let leaving = g.update(&damped, deep, Vec3::new(0.0, 0.1, 0.0), &balls, 1.0);
        assert!((pressing.y - leaving.y - 0.2).abs() < 1e-3, "{pressing} {leaving}");
    }

    #[test]
    fn bad_balls_and_a_bad_device_point_give_no_nan_force() {
        let mut g = GodObject::new();
        let balls = [
            Ball { center: Vec3::splat(f32::NAN), radius: 1.0 },
            Ball { center: Vec3::ZERO, radius: f32::INFINITY },
            Ball { center: Vec3::ZERO, radius: -1.0 },
        ];
        assert_eq!(g.update(&K, Vec3::ZERO, Vec3::ZERO, &balls, 1.0), Vec3::ZERO);
        assert_eq!(g.update(&K, Vec3::splat(f32::NAN), Vec3::ZERO, &floor(), 1.0), Vec3::ZERO);
        let no_tip = ProxyConfig { tip_radius: 0.0, ..K };
        assert_eq!(g.update(&no_tip, Vec3::new(0.0, -0.01, 0.0), Vec3::ZERO, &floor(), 1.0), Vec3::ZERO);
    }

    /// A flat floor at y = 0 given as a field (what a surface grid gives: depth and inward normal).
    struct FieldFloor;

    impl TipField for FieldFloor {
        fn overlap_and_gradient(&self, p: Vec3, tip_radius: f32) -> (f32, Vec3) {
            half_space_overlap(tip_radius, -p.y, Vec3::NEG_Y)
        }
    }

    #[test]
    fn a_floor_given_as_a_field_holds_the_tip_where_a_floor_of_balls_does() {
        let mut g = GodObject::new();
        g.update_with(&K, Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &[], &FieldFloor, 1.0);
        let f = g.update_with(&K, Vec3::new(0.0, REST - 0.002, 0.0), Vec3::ZERO, &[], &FieldFloor, 1.0);
        assert!((f - Vec3::new(0.0, 1.0, 0.0)).length() < 0.02, "{f}");
        assert!((g.proxy().y - REST).abs() < 2e-5 && (g.normal() - Vec3::Y).length() < 1e-3, "{}", g.proxy());
        // Dragged along it, frictionless: the force stays straight up (no bumps to catch on).
        for i in 1..=40 {
            let f = g.update_with(&K, Vec3::new(i as f32 * 2e-4, REST - 0.002, 0.0), Vec3::ZERO, &[], &FieldFloor, 1.0);
            assert!(f.x.abs() < 1e-4 && (f.y - 1.0).abs() < 0.02, "at step {i}: {f}");
        }
        // A wall of balls at x = 0.01 beside the field floor: an inside corner, held off both.
        let wall = [Ball { center: Vec3::new(10.01, 0.0, 0.0), radius: 10.0 }];
        let f = g.update_with(&K, Vec3::new(0.012, -0.001, 0.0), Vec3::ZERO, &wall, &FieldFloor, 1.0);
        assert!(f.x < -0.3 && f.y > 0.3 && g.proxy().x < 0.01, "{f}, proxy {}", g.proxy());
    }

    #[test]
    fn the_half_space_overlap_is_a_cap_and_its_gradient_its_derivative() {
        let (v, _) = half_space_overlap(R, -R, Vec3::NEG_Y);
        assert_eq!(v, 0.0, "touching from outside: nothing");
        let (v, _) = half_space_overlap(R, R, Vec3::NEG_Y);
        assert!((v - 4.0 / 3.0 * PI * R.powi(3)).abs() < 1e-12, "all in: the whole ball");
        let h = 1e-6;
        for depth in [-0.0015, -0.0008, 0.0, 0.0011] {
            let (_, g) = half_space_overlap(R, depth, Vec3::NEG_Y);
            let numeric = (half_space_overlap(R, depth + h, Vec3::NEG_Y).0
                - half_space_overlap(R, depth - h, Vec3::NEG_Y).0)
                / (2.0 * h);
            assert!((numeric + g.y).abs() < 1e-3 * numeric.abs() + 1e-12, "at {depth}: {numeric} vs {}", -g.y);
        }
    }

    #[test]
    fn the_gradient_is_the_derivative_of_the_volume() {
        let balls = [Ball { center: Vec3::new(0.001, -0.002, 0.0005), radius: 0.003 }];
        let surface = Surface { balls: &balls, field: &(), tip: R, level: 0.0 };
        let p = Vec3::new(0.0, 0.002, 0.0);
        let (_, g) = surface.volume_and_gradient(p);
        let h = 1e-5;
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let numeric = (surface.volume(p + axis * h) - surface.volume(p - axis * h)) / (2.0 * h);
            assert!((numeric - g.dot(axis)).abs() < 1e-3 * g.length() + 1e-12, "{axis}: {numeric} vs {}", g.dot(axis));
        }
    }
}
