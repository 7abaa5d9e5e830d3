//! Where a query's overlapping pairs go: nowhere (volume only) or into a [`ContactSet`].

use super::affine::WideAffine;
use crate::shape::{Lens, Lens4};
use glam::{Affine3A, Vec3, Vec4};
use haptic_common::{Contact, ContactSet};

/// Receives the overlapping pairs a query finds, in A's frame: the lens (volume already weighted)
/// and the two centres its normal runs between (from B's towards A's).
pub(super) trait Sink {
    /// One pair.
    fn one(&mut self, lens: &Lens, ca: Vec3, cb: Vec3);
    /// Four sphere pairs at once; only the lanes whose bit is set in `lanes` count.
    fn four(&mut self, lenses: &Lens4, ca: [Vec4; 3], cb: [Vec4; 3], lanes: u32);

    /// Eight sphere pairs at once (lane by lane as [`Sink::four`] takes them); only the lanes whose bit
    /// is set in `lanes` count.
    #[inline(always)]
    fn eight(&mut self, lenses: &Lens8, ca: &[[f32; 8]; 3], cb: &[[f32; 8]; 3], lanes: u32) {
        for half in [0, 4] {
            let v = |a: &[f32; 8]| Vec4::from_slice(&a[half..half + 4]);
            let lens = Lens4 {
                volume: v(&lenses.volume),
                centroid: [v(&lenses.centroid[0]), v(&lenses.centroid[1]), v(&lenses.centroid[2])],
                depth: v(&lenses.depth),
                inv_d: v(&lenses.inv_d),
            };
            let (ca, cb) = ([v(&ca[0]), v(&ca[1]), v(&ca[2])], [v(&cb[0]), v(&cb[1]), v(&cb[2])]);
            self.four(&lens, ca, cb, lanes >> half & 0xf);
        }
    }

    /// True for a sink that collects a neighbour list ([`super::coherent`]): the descent then tests
    /// with [`Sink::margin`] and hands over candidates ([`Sink::pair`], [`Sink::nested`]) instead of
    /// computing lenses. Known at compile time, so the other queries carry none of it.
    const COLLECTS: bool = false;

    /// The skin the candidates are collected with.
    fn margin(&self) -> f32 {
        0.0
    }

    /// A's sphere `sa` and B's sphere `sb` come within the margin.
    fn pair(&mut self, _sa: u32, _sb: u32) {}

    /// A node's bound (`inner`) lies inside a leaf sphere (`outer`) of the other tree with the margin
    /// to spare, standing for `volume` of overlap: `ca`/`ra` on A's side (A's frame), `pb` on B's
    /// (B's frame); `b_inside` when B's node is the one inside A's sphere.
    fn nested(&mut self, _ca: Vec3, _ra: f32, _pb: crate::shape::Sphere, _volume: f32, _b_inside: bool) {}

    /// A's inner node `node` lies inside B's sphere `sb` (in leaf `ib`) but nearer its surface than the
    /// margin: inside it stands for its mesh share times the sphere's weight, else its subtree must be
    /// descended against the sphere.
    fn maybe_nested(&mut self, _node: u32, _sb: u32, _ib: u32) {}
}

/// Keeps nothing: the query's result carries the volume.
pub(super) struct VolumeOnly;

impl Sink for VolumeOnly {
    #[inline(always)]
    fn one(&mut self, _: &Lens, _: Vec3, _: Vec3) {}
    #[inline(always)]
    fn four(&mut self, _: &Lens4, _: [Vec4; 3], _: [Vec4; 3], _: u32) {}
}

/// Writes each pair as a world-frame contact.
pub(super) struct Contacts<'o> {
    to_world: Affine3A,
    wide: WideAffine,
    /// Normal used when two centres coincide.
    fallback: Vec3,
    out: &'o mut ContactSet,
}

/// Centres closer than this (squared) give no direction: the fallback normal is used.
const COINCIDENT: f32 = 1e-24;

impl<'o> Contacts<'o> {
    /// `to_world` maps A's frame to the world.
    pub(super) fn new(to_world: Affine3A, fallback: Vec3, out: &'o mut ContactSet) -> Self {
        Self { to_world, wide: WideAffine::new(&to_world), fallback, out }
    }
}

/// Eight lenses (volumes weighted), lane by lane as [`Lens4`] holds four.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Lens8 {
    pub volume: [f32; 8],
    pub centroid: [[f32; 8]; 3],
    pub depth: [f32; 8],
    pub inv_d: [f32; 8],
}

impl Sink for Contacts<'_> {
    /// As [`Contacts::four`] over eight lanes, in the same order of operations (so the same bits): the
    /// normals and points moved into the world by plain loops, eight-wide where the caller is compiled so.
    #[inline(always)]
    fn eight(&mut self, l: &Lens8, ca: &[[f32; 8]; 3], cb: &[[f32; 8]; 3], mut lanes: u32) {
        let m = &self.to_world;
        let (mx, my, mz, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
        let (mut normal, mut point) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
        for i in 0..8 {
            let inv = l.inv_d[i];
            let (x, y, z) = ((ca[0][i] - cb[0][i]) * inv, (ca[1][i] - cb[1][i]) * inv, (ca[2][i] - cb[2][i]) * inv);
            normal[0][i] = mx.x * x + my.x * y + mz.x * z;
            normal[1][i] = mx.y * x + my.y * y + mz.y * z;
            normal[2][i] = mx.z * x + my.z * y + mz.z * z;
            let (x, y, z) = (l.centroid[0][i], l.centroid[1][i], l.centroid[2][i]);
            point[0][i] = mx.x * x + my.x * y + mz.x * z + t.x;
            point[1][i] = mx.y * x + my.y * y + mz.y * z + t.y;
            point[2][i] = mx.z * x + my.z * y + mz.z * z + t.z;
        }
        let coincident = COINCIDENT.sqrt().recip();
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let normal = if l.inv_d[i] >= coincident {
                self.fallback
            } else {
                Vec3::new(normal[0][i], normal[1][i], normal[2][i])
            };
            self.out.push(Contact {
                point: Vec3::new(point[0][i], point[1][i], point[2][i]),
                normal,
                volume: l.volume[i],
                depth: l.depth[i],
            });
        }
    }

    #[inline]
    fn one(&mut self, lens: &Lens, ca: Vec3, cb: Vec3) {
        let delta = ca - cb;
        let len2 = delta.length_squared();
        let normal = if len2 > COINCIDENT {
            self.to_world.transform_vector3(delta * len2.sqrt().recip())
        } else {
            self.fallback
        };
        self.out.push(Contact {
            point: self.to_world.transform_point3(lens.centroid),
            normal,
            volume: lens.volume,
            depth: lens.depth,
        });
    }

    #[inline]
    fn four(&mut self, lenses: &Lens4, ca: [Vec4; 3], cb: [Vec4; 3], mut lanes: u32) {
        let delta = [ca[0] - cb[0], ca[1] - cb[1], ca[2] - cb[2]];
        let inv = lenses.inv_d;
        let normal = self.wide.vector(delta[0] * inv, delta[1] * inv, delta[2] * inv);
        let point = self.wide.point(lenses.centroid[0], lenses.centroid[1], lenses.centroid[2]);
        // |d| <= 1e-12, as |d|² <= COINCIDENT.
        let coincident = inv.cmpge(Vec4::splat(COINCIDENT.sqrt().recip())).bitmask();
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let normal = if coincident >> lane & 1 != 0 {
                self.fallback
            } else {
                Vec3::new(normal[0][lane], normal[1][lane], normal[2][lane])
            };
            self.out.push(Contact {
                point: Vec3::new(point[0][lane], point[1][lane], point[2][lane]),
                normal,
                volume: lenses.volume[lane],
                depth: lenses.depth[lane],
            });
        }
    }
}
