//! A neighbour list's candidate pairs evaluated eight at a time: their distances, then the lenses and
//! contacts of those that overlap ([`Sink::eight`]). Plain loops over eight lanes, compiled twice — for
//! AVX2 (eight-wide, chosen at run time where the CPU has it) and for the baseline (SSE2, four-wide) —
//! with the same operations in the same order as `WideAffine::point` and [`lens_x4`], so either gives the
//! same bits as the other and as the four-wide path.
//!
//! [`lens_x4`]: crate::shape::lens_x4

use crate::query::overlap::sink::{Lens8, Sink};
use glam::{Affine3A, Vec4};
use std::f32::consts::PI;

/// Lanes per group.
pub(super) const LANES: usize = 8;

/// Eight overlapping sphere pairs, both sides in A's frame, and the weights' products.
#[derive(Clone, Copy, Debug, Default)]
struct Pairs8 {
    ca: [[f32; LANES]; 3],
    ra: [f32; LANES],
    cb: [[f32; LANES]; 3],
    rb: [f32; LANES],
    w: [f32; LANES],
}

/// What the groups added: weighted volume and overlapping pairs.
#[derive(Clone, Copy, Default)]
pub(super) struct Found {
    pub volume: f32,
    pub pairs: u32,
}

/// The pair list's rows `0..len` (columns: A's centre and radius in A's frame, B's in B's frame, the
/// weight; padded with zero rows to a multiple of eight): their distances eight at a time, the pairs that
/// overlap gathered eight to a group, their lenses (B's centres moved into A's frame by `pos12`) into
/// `sink`.
pub(super) fn pairs(cols: &[Vec<f32>; 9], len: usize, pos12: &Affine3A, sink: &mut impl Sink) -> Found {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, the only feature `pairs_avx2` is compiled for.
        return unsafe { pairs_avx2(cols, len, pos12, sink) };
    }
    pairs_of(cols, len, pos12, sink)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn pairs_avx2(cols: &[Vec<f32>; 9], len: usize, pos12: &Affine3A, sink: &mut impl Sink) -> Found {
    pairs_of(cols, len, pos12, sink)
}

#[inline(always)]
fn pairs_of(cols: &[Vec<f32>; 9], len: usize, m: &Affine3A, sink: &mut impl Sink) -> Found {
    let (mx, my, mz, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
    let mut found = Found::default();
    let (mut group, mut lane) = (Pairs8::default(), 0);
    let mut l = Lens8::default();
    for at in (0..len).step_by(LANES) {
        let row = |k: usize| -> &[f32; LANES] { cols[k][at..at + LANES].try_into().expect("rows come in eights") };
        let (ax, ay, az, ar, bx, by, bz, br) = (row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7));
        let (mut cb, mut hits) = ([[0.0f32; LANES]; 3], 0u32);
        for i in 0..LANES {
            // As `WideAffine::point`: the linear part's sum first, then the shift.
            cb[0][i] = mx.x * bx[i] + my.x * by[i] + mz.x * bz[i] + t.x;
            cb[1][i] = mx.y * bx[i] + my.y * by[i] + mz.y * bz[i] + t.y;
            cb[2][i] = mx.z * bx[i] + my.z * by[i] + mz.z * bz[i] + t.z;
            let (dx, dy, dz) = (ax[i] - cb[0][i], ay[i] - cb[1][i], az[i] - cb[2][i]);
            let reach = ar[i] + br[i];
            hits |= ((dx * dx + dy * dy + dz * dz < reach * reach) as u32) << i;
        }
        // Most candidates are still apart; the others join the group.
        while hits != 0 {
            let i = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            for (g, c) in group.cb.iter_mut().zip(&cb) {
                g[lane] = c[i];
            }
            (group.ca[0][lane], group.ca[1][lane], group.ca[2][lane]) = (ax[i], ay[i], az[i]);
            (group.ra[lane], group.rb[lane], group.w[lane]) = (ar[i], br[i], cols[8][at + i]);
            lane += 1;
            if lane == LANES {
                emit(&group, &mut l, sink, &mut found);
                lane = 0;
            }
        }
    }
    if lane > 0 {
        // Empty lanes: zero radii, apart.
        for i in lane..LANES {
            (group.ra[i], group.rb[i], group.w[i]) = (0.0, 0.0, 0.0);
        }
        emit(&group, &mut l, sink, &mut found);
    }
    found
}

/// The lenses of one group into `sink`.
#[inline(always)]
fn emit(group: &Pairs8, l: &mut Lens8, sink: &mut impl Sink, found: &mut Found) {
    lens8(group, l);
    let mut lanes = 0;
    for i in 0..LANES {
        lanes |= ((l.volume[i] > 0.0) as u32) << i;
    }
    if lanes != 0 {
        // In lane order, as the four-wide sum would add them.
        for half in [0, 4] {
            found.volume += Vec4::from_slice(&l.volume[half..half + 4]).element_sum();
        }
        found.pairs += lanes.count_ones();
        sink.eight(l, &group.ca, &group.cb, lanes);
    }
}

/// [`crate::shape::lens_x4`] lane by lane over eight pairs (B's centres already in A's frame).
#[inline(always)]
fn lens8(p: &Pairs8, out: &mut Lens8) {
    for i in 0..LANES {
        let c2 = [p.cb[0][i], p.cb[1][i], p.cb[2][i]];
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
    use crate::query::overlap::sink::Contacts;
    use crate::shape::{Lens4, lens_x4};
    use glam::{Quat, Vec3};
    use haptic_common::ContactSet;
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

    /// The four-wide path over the rows: each four rows' lenses into `sink`.
    fn four_wide(cols: &[Vec<f32>; 9], len: usize, m: &Affine3A, sink: &mut impl Sink) {
        let wide = WideAffine::new(m);
        for at in (0..len).step_by(4) {
            let v = |k: usize| Vec4::from_slice(&cols[k][at..at + 4]);
            let ca = [v(0), v(1), v(2)];
            let cb = wide.point(v(4), v(5), v(6));
            let mut l = lens_x4(ca, v(3), cb, v(7));
            l.volume *= v(8);
            sink.four(&l, ca, cb, l.volume.cmpgt(Vec4::ZERO).bitmask());
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop, reason = "a row fills nine columns")]
    fn eight_lanes_give_the_four_wide_lens_bit_for_bit_on_either_instruction_set() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let m = Affine3A::from_rotation_translation(
            Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.9, 1.7),
            Vec3::new(0.3, -0.1, 0.2),
        );
        // 4,001 rows (padded with zero rows to a multiple of eight): some coincident centres, some
        // nested, most apart or in a lens.
        let len: usize = 4001;
        let mut cols: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; len.next_multiple_of(LANES)]);
        for r in 0..len {
            for k in 0..3 {
                cols[k][r] = rng.random_range(-1.0..1.0);
                cols[4 + k][r] = rng.random_range(-1.0..1.0);
            }
            if r % 8 == 3 {
                let c = m.inverse().transform_point3(Vec3::new(cols[0][r], cols[1][r], cols[2][r]));
                (cols[4][r], cols[5][r], cols[6][r]) = (c.x, c.y, c.z);
            }
            cols[3][r] = rng.random_range(0.0..1.0);
            cols[7][r] = rng.random_range(0.0..1.0);
            cols[8][r] = rng.random_range(1.0..3.0);
        }
        let mut expected = Record::default();
        four_wide(&cols, len, &m, &mut expected);
        assert!(expected.0.len() > 1000, "the pairs overlap often enough to test: {}", expected.0.len());
        let bits = |r: &Record| r.0.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut baseline = Record::default();
        pairs_of(&cols, len, &m, &mut baseline);
        assert_eq!(bits(&baseline), bits(&expected), "baseline build");
        let mut dispatched = Record::default();
        let found = pairs(&cols, len, &m, &mut dispatched);
        assert_eq!(bits(&dispatched), bits(&expected), "the build chosen for this CPU");
        assert_eq!(found.pairs as usize, expected.0.len());

        // And the world-frame contacts, written eight at a time, as the four-wide sink writes them.
        let to_world = Affine3A::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(1.0, 2.0, -0.5));
        let contacts = |run: &dyn Fn(&mut Contacts)| {
            let mut set = ContactSet::new();
            run(&mut Contacts::new(to_world, Vec3::Y, &mut set));
            set.as_slice()
                .iter()
                .flat_map(|c| [c.point.to_array(), c.normal.to_array(), [c.volume, c.depth, 0.0]])
                .flatten()
                .map(f32::to_bits)
                .collect::<Vec<_>>()
        };
        let four_wide = contacts(&|sink| four_wide(&cols, len, &m, sink));
        assert!(four_wide.len() > 1000 * 9);
        assert_eq!(
            contacts(&|sink| {
                pairs_of(&cols, len, &m, sink);
            }),
            four_wide,
            "baseline build"
        );
        assert_eq!(
            contacts(&|sink| {
                pairs(&cols, len, &m, sink);
            }),
            four_wide,
            "the build chosen for this CPU"
        );
    }
}
