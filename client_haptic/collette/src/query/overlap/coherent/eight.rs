//! The lenses of a neighbour list's overlapping sphere pairs, eight at a time: plain loops over eight
//! lanes, compiled twice — for AVX2 (eight-wide, chosen at run time where the CPU has it) and for the
//! baseline (SSE2, four-wide) — with the same operations in the same order as [`lens_x4`], so either
//! gives the same bits as the other and as the four-wide lens.
//!
//! [`lens_x4`]: crate::shape::lens_x4

use crate::query::overlap::sink::Sink;
use crate::shape::Lens4;
use glam::{Affine3A, Vec4};
use std::f32::consts::PI;

/// Lanes per group.
pub(super) const LANES: usize = 8;

/// Eight sphere pairs: A's centres and radii in A's frame, B's in B's frame, the weights' products.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Pairs8 {
    pub ca: [[f32; LANES]; 3],
    pub ra: [f32; LANES],
    pub cb: [[f32; LANES]; 3],
    pub rb: [f32; LANES],
    pub w: [f32; LANES],
}

/// Their lenses (volumes weighted), with B's centres moved into A's frame.
#[derive(Clone, Copy, Default)]
struct Lenses8 {
    volume: [f32; LANES],
    centroid: [[f32; LANES]; 3],
    depth: [f32; LANES],
    inv_d: [f32; LANES],
    cb: [[f32; LANES]; 3],
}

/// What the groups added: weighted volume and overlapping pairs.
#[derive(Clone, Copy, Default)]
pub(super) struct Found {
    pub volume: f32,
    pub pairs: u32,
}

/// The lenses of `groups` (B's centres moved into A's frame by `pos12`) into `sink`.
pub(super) fn lenses(groups: &[Pairs8], pos12: &Affine3A, sink: &mut impl Sink) -> Found {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, the only feature `lenses_avx2` is compiled for.
        return unsafe { lenses_avx2(groups, pos12, sink) };
    }
    lenses_of(groups, pos12, sink)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lenses_avx2(groups: &[Pairs8], pos12: &Affine3A, sink: &mut impl Sink) -> Found {
    lenses_of(groups, pos12, sink)
}

#[inline(always)]
fn lenses_of(groups: &[Pairs8], pos12: &Affine3A, sink: &mut impl Sink) -> Found {
    let mut found = Found::default();
    let mut l = Lenses8::default();
    for p in groups {
        lens8(p, pos12, &mut l);
        for half in [0, 4] {
            let v = |a: &[f32; LANES]| Vec4::from_slice(&a[half..half + 4]);
            let lens = Lens4 {
                volume: v(&l.volume),
                centroid: [v(&l.centroid[0]), v(&l.centroid[1]), v(&l.centroid[2])],
                depth: v(&l.depth),
                inv_d: v(&l.inv_d),
            };
            let lanes = lens.volume.cmpgt(Vec4::ZERO).bitmask();
            if lanes != 0 {
                found.volume += lens.volume.element_sum();
                found.pairs += lanes.count_ones();
                let ca = [v(&p.ca[0]), v(&p.ca[1]), v(&p.ca[2])];
                sink.four(&lens, ca, [v(&l.cb[0]), v(&l.cb[1]), v(&l.cb[2])], lanes);
            }
        }
    }
    found
}

/// [`crate::shape::lens_x4`] lane by lane over eight pairs, after moving B's centres by `m`.
#[inline(always)]
fn lens8(p: &Pairs8, m: &Affine3A, out: &mut Lenses8) {
    let (mx, my, mz, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
    for i in 0..LANES {
        let (x, y, z) = (p.cb[0][i], p.cb[1][i], p.cb[2][i]);
        // As `WideAffine::point`: the linear part's sum first, then the shift.
        let c2 = [
            mx.x * x + my.x * y + mz.x * z + t.x,
            mx.y * x + my.y * y + mz.y * z + t.y,
            mx.z * x + my.z * y + mz.z * z + t.z,
        ];
        let c1 = [p.ca[0][i], p.ca[1][i], p.ca[2][i]];
        let (r1, r2) = (p.ra[i], p.rb[i]);
        let delta = [c2[0] - c1[0], c2[1] - c1[1], c2[2] - c1[2]];
        let d2 = delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2];
        let s = r1 + r2;
        let apart = d2 >= s * s;
        let d = d2.sqrt();
        let inside = d <= (r1 - r2).abs();
        let inv_d = 1.0 / d;
        let x1 = (d2 + r1 * r1 - r2 * r2) * 0.5 * inv_d;
        let h1 = (r1 - x1).max(0.0).min(r1 * 2.0);
        let h2 = (r2 - (d - x1)).max(0.0).min(r2 * 2.0);
        let third = PI / 3.0;
        let v1 = third * h1 * h1 * (r1 * 3.0 - h1);
        let v2 = third * h2 * h2 * (r2 * 3.0 - h2);
        let (a1, a2) = (h1 * (r1 * 2.0 - h1), h2 * (r2 * 2.0 - h2));
        let moment = PI * 0.25 * (a1 * a1 - a2 * a2) * inv_d;
        let lens_volume = v1 + v2;
        let inv_v = 1.0 / lens_volume;
        let small_r = r1.min(r2);
        let small_volume = 4.0 / 3.0 * PI * small_r * small_r * small_r;
        for k in 0..3 {
            let lens_c = (c1[k] * v1 + c2[k] * v2 + delta[k] * moment) * inv_v;
            let small_c = if r1 <= r2 { c1[k] } else { c2[k] };
            out.centroid[k][i] = if inside { small_c } else { lens_c };
            out.cb[k][i] = c2[k];
        }
        let volume = if inside { small_volume } else { lens_volume.max(0.0) };
        out.volume[i] = if apart { 0.0 } else { volume } * p.w[i];
        out.depth[i] = s - d;
        out.inv_d[i] = inv_d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query::overlap::affine::WideAffine;
    use crate::shape::lens_x4;
    use glam::{Quat, Vec3};
    use rand::{Rng, SeedableRng};

    /// Records what a sink is given, lane by lane.
    #[derive(Default)]
    struct Record(Vec<[f32; 9]>);

    impl Sink for Record {
        fn one(&mut self, _: &crate::shape::Lens, _: Vec3, _: Vec3) {}
        fn four(&mut self, l: &Lens4, ca: [Vec4; 3], cb: [Vec4; 3], lanes: u32) {
            for i in (0..4).filter(|i| lanes >> i & 1 != 0) {
                self.0.push([
                    l.volume[i],
                    l.centroid[0][i],
                    l.centroid[1][i],
                    l.centroid[2][i],
                    l.depth[i],
                    l.inv_d[i],
                    ca[0][i],
                    cb[0][i],
                    cb[2][i],
                ]);
            }
        }
    }

    #[test]
    fn eight_lanes_give_the_four_wide_lens_bit_for_bit_on_either_instruction_set() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let m = Affine3A::from_rotation_translation(
            Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.9, 1.7),
            Vec3::new(0.3, -0.1, 0.2),
        );
        let mut groups = vec![Pairs8::default(); 500];
        for g in &mut groups {
            for i in 0..LANES {
                for k in 0..3 {
                    g.ca[k][i] = rng.random_range(-1.0..1.0);
                    g.cb[k][i] = rng.random_range(-1.0..1.0);
                }
                // Some coincident centres, some nested, most apart or in a lens.
                if i == 3 {
                    let c = m.inverse().transform_point3(Vec3::new(g.ca[0][i], g.ca[1][i], g.ca[2][i]));
                    (g.cb[0][i], g.cb[1][i], g.cb[2][i]) = (c.x, c.y, c.z);
                }
                g.ra[i] = rng.random_range(0.0..1.0);
                g.rb[i] = rng.random_range(0.0..1.0);
                g.w[i] = rng.random_range(1.0..3.0);
            }
        }
        let wide = WideAffine::new(&m);
        let mut expected = Record::default();
        for g in &groups {
            for half in [0, 4] {
                let v = |a: &[f32; LANES]| Vec4::from_slice(&a[half..half + 4]);
                let ca = [v(&g.ca[0]), v(&g.ca[1]), v(&g.ca[2])];
                let cb = wide.point(v(&g.cb[0]), v(&g.cb[1]), v(&g.cb[2]));
                let mut l = lens_x4(ca, v(&g.ra), cb, v(&g.rb));
                l.volume *= v(&g.w);
                expected.four(&l, ca, cb, l.volume.cmpgt(Vec4::ZERO).bitmask());
            }
        }
        assert!(expected.0.len() > 1000, "the pairs overlap often enough to test: {}", expected.0.len());
        let bits = |r: &Record| r.0.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut baseline = Record::default();
        lenses_of(&groups, &m, &mut baseline);
        assert_eq!(bits(&baseline), bits(&expected), "baseline build");
        let mut dispatched = Record::default();
        let found = lenses(&groups, &m, &mut dispatched);
        assert_eq!(bits(&dispatched), bits(&expected), "the build chosen for this CPU");
        assert_eq!(found.pairs as usize, expected.0.len());
    }
}
