//! The 3-DOF proxy (god-object) force for point tools.
//!
//! You need this module when the tool is a point (a stylus tip). The proxy stays on the surface while
//! the device point sinks in; a spring pulls the device towards the proxy. Friction keeps the proxy in
//! place while the tangential pull stays inside the friction cone.
//!
//! Point-probe contacts use [`haptic_common::Contact`] this way: `point` is the probe position,
//! `normal` the outward surface normal, `depth` the penetration, so the surface point is
//! `point + depth · normal`.

use glam::Vec3;
use haptic_common::ContactSet;

use crate::error::{Result, non_negative, positive};

/// Parameters of the proxy force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyConfig {
    /// Spring between proxy and device, N/m (default 300).
    pub stiffness_n_per_m: f32,
    /// Damping of the approach speed along the contact normal, N·s/m (default 0.5).
    pub damping_ns_per_m: f32,
    /// Static friction coefficient (default 0.3).
    pub friction: f32,
}

impl Default for ProxyConfig {
    fn default() -> Self {
        Self { stiffness_n_per_m: 300.0, damping_ns_per_m: 0.5, friction: 0.3 }
    }
}

impl ProxyConfig {
    /// Checks every value.
    pub fn validate(&self) -> Result<()> {
        positive("stiffness_n_per_m", self.stiffness_n_per_m)?;
        non_negative("damping_ns_per_m", self.damping_ns_per_m)?;
        non_negative("friction", self.friction)
    }
}

/// The proxy's state.
#[derive(Clone, Debug)]
pub struct Proxy3Dof {
    config: ProxyConfig,
    proxy: Vec3,
    in_contact: bool,
}

impl Proxy3Dof {
    /// A proxy that starts on the device.
    pub fn new(config: ProxyConfig) -> Self {
        Self { config, proxy: Vec3::ZERO, in_contact: false }
    }

    /// The proxy position, m.
    pub fn proxy(&self) -> Vec3 {
        self.proxy
    }

    /// True when the last update found contact.
    pub fn in_contact(&self) -> bool {
        self.in_contact
    }

    /// Updates the proxy for a device point at `device` moving at `velocity` against `contacts`, and
    /// returns the force on the device, N. Allocation-free; non-finite contacts are ignored.
    pub fn update(&mut self, device: Vec3, velocity: Vec3, contacts: &ContactSet) -> Vec3 {
        if !device.is_finite() {
            return Vec3::ZERO;
        }
        let planes = || {
            contacts.as_slice().iter().filter_map(|c| {
                let n = c.normal.try_normalize()?;
                let s = c.point + n * c.depth;
                (s.is_finite() && c.depth.is_finite()).then_some((n, s))
            })
        };
        // Project the device point out of every constraint half-space (a few sweeps settle corners).
        let project = |mut p: Vec3| {
            for _ in 0..4 {
                for (n, s) in planes() {
                    let d = (p - s).dot(n);
                    if d < 0.0 {
                        p -= d * n;
                    }
                }
            }
            p
        };
        let candidate = project(device);
        if candidate == device {
            self.proxy = device;
            self.in_contact = false;
            return Vec3::ZERO;
        }
        let mut proxy = candidate;
        if self.in_contact && self.proxy.is_finite() {
            // Friction: stay put while the tangential offset is inside the cone mu * penetration.
            let held = project(self.proxy);
            let penetration = (candidate - device).length();
            let slide = candidate - held;
            let cone = self.config.friction * penetration;
            let len = slide.length();
            proxy = if len <= cone { held } else { held + slide * ((len - cone) / len) };
        }
        self.proxy = proxy;
        self.in_contact = true;
        let spring = self.config.stiffness_n_per_m * (proxy - device);
        let n = spring.normalize_or_zero();
        let approach = velocity.dot(n).min(0.0); // only damp motion into the surface
        let force = spring - self.config.damping_ns_per_m * approach * n;
        if force.is_finite() { force } else { Vec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use haptic_common::Contact;

    use super::*;

    fn floor_contact(device: Vec3) -> ContactSet {
        let mut s = ContactSet::new();
        if device.y < 0.0 {
            s.push(Contact { point: device, normal: Vec3::Y, volume: 0.0, depth: -device.y });
        }
        s
    }

    #[test]
    fn a_point_below_a_floor_is_pushed_up_by_stiffness_times_depth() {
        let mut p = Proxy3Dof::new(ProxyConfig { friction: 0.0, ..Default::default() });
        let dev = Vec3::new(0.0, -0.002, 0.0);
        let f = p.update(dev, Vec3::ZERO, &floor_contact(dev));
        assert!((f - Vec3::new(0.0, 0.6, 0.0)).length() < 1e-5, "{f:?}");
        assert!(p.proxy().y.abs() < 1e-7);
    }

    #[test]
    fn free_space_gives_no_force() {
        let mut p = Proxy3Dof::new(ProxyConfig::default());
        let dev = Vec3::new(0.0, 0.01, 0.0);
        assert_eq!(p.update(dev, Vec3::ONE, &floor_contact(dev)), Vec3::ZERO);
        assert!(!p.in_contact());
    }

    #[test]
    fn friction_holds_the_proxy_until_the_pull_leaves_the_cone() {
        let mut p = Proxy3Dof::new(ProxyConfig { friction: 0.5, ..Default::default() });
        let d0 = Vec3::new(0.0, -0.002, 0.0);
        p.update(d0, Vec3::ZERO, &floor_contact(d0));
        let d1 = Vec3::new(0.0005, -0.002, 0.0); // inside the cone: 0.5 * 2 mm = 1 mm
        let f = p.update(d1, Vec3::ZERO, &floor_contact(d1));
        assert!(f.x < 0.0, "friction pulls back: {f:?}");
        assert!(p.proxy().x.abs() < 1e-7);
        let d2 = Vec3::new(0.003, -0.002, 0.0);
        p.update(d2, Vec3::ZERO, &floor_contact(d2));
        assert!((p.proxy().x - 0.002).abs() < 1e-6, "slides to the cone's edge: {:?}", p.proxy());
    }

    #[test]
    fn a_corner_pushes_out_along_both_walls() {
        let mut p = Proxy3Dof::new(ProxyConfig { friction: 0.0, ..Default::default() });
        let dev = Vec3::new(-0.001, -0.001, 0.0);
        let mut s = ContactSet::new();
        s.push(Contact { point: dev, normal: Vec3::Y, volume: 0.0, depth: 0.001 });
        s.push(Contact { point: dev, normal: Vec3::X, volume: 0.0, depth: 0.001 });
        let f = p.update(dev, Vec3::ZERO, &s);
        assert!((f - Vec3::new(0.3, 0.3, 0.0)).length() < 1e-5, "{f:?}");
    }

    #[test]
    fn nan_contacts_give_no_nan_force() {
        let mut p = Proxy3Dof::new(ProxyConfig::default());
        let mut s = ContactSet::new();
        s.push(Contact { point: Vec3::splat(f32::NAN), normal: Vec3::Y, volume: 0.0, depth: 1.0 });
        s.push(Contact { point: Vec3::ZERO, normal: Vec3::Y, volume: 0.0, depth: f32::INFINITY });
        assert!(p.update(Vec3::ZERO, Vec3::ZERO, &s).is_finite());
    }
}
