//! Thrown items in flight: the server lands a throw at once (the guards hear the thud where it lands);
//! the player sees the item leave the hand and fly there along a ballistic arc.
//!
//! You need this module to draw a throw: [`Flight::between`] plans the arc from the hand to the landing
//! point, [`Flight::at`] gives the drawn position at any time after the throw.

use glam::Vec3;

/// Gravity, m/s² (down is −y in Bevy's world).
pub const GRAVITY_M_S2: f32 = 9.81;
/// Shortest flight drawn, seconds (a drop at the feet still falls visibly).
pub const MIN_FLIGHT_S: f32 = 0.25;

/// Time in the air of a throw over `horizontal_m` metres: that of a 45° throw on level ground (√(2d/g)),
/// at least [`MIN_FLIGHT_S`]. The thud is heard when it lands.
pub fn flight_time_s(horizontal_m: f32) -> f32 {
    (2.0 * horizontal_m.max(0.0) / GRAVITY_M_S2).sqrt().max(MIN_FLIGHT_S)
}

/// A ballistic flight from a hand to a landing point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flight {
    /// Where it left the hand (world).
    pub from: Vec3,
    /// Where it lands (world).
    pub to: Vec3,
    /// Clock time of the throw, seconds.
    pub start_s: f64,
    /// Time in the air, seconds.
    pub duration_s: f32,
    /// Launch velocity, m/s.
    pub velocity: Vec3,
}

impl Flight {
    /// The arc of a throw at `start_s` from `from` to `to`: the time in the air is [`flight_time_s`] of
    /// the horizontal distance; the launch velocity follows so that gravity alone brings it to `to` then.
    pub fn between(from: Vec3, to: Vec3, start_s: f64) -> Self {
        let duration_s = flight_time_s(Vec3::new(to.x - from.x, 0.0, to.z - from.z).length());
        let velocity = (to - from) / duration_s + Vec3::Y * (0.5 * GRAVITY_M_S2 * duration_s);
        Self { from, to, start_s, duration_s, velocity }
    }

    /// Where it is at clock time `now_s` (at the hand before the throw), or `None` once it has landed.
    pub fn at(&self, now_s: f64) -> Option<Vec3> {
        let t = (now_s - self.start_s).max(0.0) as f32;
        if t >= self.duration_s {
            return None;
        }
        Some(self.from + self.velocity * t - Vec3::Y * (0.5 * GRAVITY_M_S2 * t * t))
    }

    /// The highest point of the arc.
    pub fn apex(&self) -> Vec3 {
        let t = (self.velocity.y / GRAVITY_M_S2).clamp(0.0, self.duration_s);
        self.from + self.velocity * t - Vec3::Y * (0.5 * GRAVITY_M_S2 * t * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_arc_leaves_the_hand_lands_on_the_point_and_falls_under_gravity_alone() {
        let (from, to) = (Vec3::new(0.0, 1.2, 0.0), Vec3::new(6.0, 0.08, -4.0));
        let f = Flight::between(from, to, 10.0);
        let d = Vec3::new(6.0, 0.0, -4.0).length();
        assert!((f.duration_s - (2.0 * d / GRAVITY_M_S2).sqrt()).abs() < 1e-5);
        assert!(f.at(10.0).is_some_and(|p| p.distance(from) < 1e-6), "starts in the hand");
        let end = f.from + f.velocity * f.duration_s - Vec3::Y * (0.5 * GRAVITY_M_S2 * f.duration_s * f.duration_s);
        assert!(end.distance(to) < 1e-4, "ends on the landing point: {end}");
        assert!(f.at(10.0 + f.duration_s as f64 + 1e-3).is_none(), "then it has landed");
        assert!(f.apex().y > from.y + 1.0, "it rises well above the hand: {}", f.apex());
        // Sampled every 10 ms: horizontal speed constant, vertical acceleration −g.
        let dt = 0.01f32;
        let samples: Vec<Vec3> =
            (0..).map(|k| f.at(10.0 + (k as f32 * dt) as f64)).take_while(Option::is_some).flatten().collect();
        assert!(samples.len() > 50);
        for w in samples.windows(3) {
            let accel = (w[2] - 2.0 * w[1] + w[0]) / (dt * dt);
            assert!((accel - Vec3::Y * -GRAVITY_M_S2).length() < 0.05, "acceleration {accel}");
        }
    }

    #[test]
    fn a_drop_at_the_feet_still_takes_the_shortest_flight() {
        let f = Flight::between(Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 0.08, 1.0), 0.0);
        assert_eq!(f.duration_s, MIN_FLIGHT_S);
        assert!(f.at(0.2).is_some_and(|p| p.y > 0.08 && p.x == 1.0));
    }
}
