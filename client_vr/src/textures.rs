//! The museum's surfaces, painted at start-up (no downloaded assets): a parquet floor, painted plaster
//! walls and marble pedestals. Each is a tileable square of linear RGB made from seeded value noise, then
//! an sRGB image with its whole mip chain (so a floor seen at a grazing angle stays calm instead of
//! shimmering) and a repeating sampler: meshes give their UVs in metres over [`TILE_M`].
//!
//! You need this module to change how a surface looks; [`crate::palette`] makes the images.

use bevy::asset::RenderAssetUsages;
use bevy::image::{ImageAddressMode, ImageSampler, ImageSamplerDescriptor};
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};

/// Side of every texture, pixels.
pub const SIZE: usize = 256;
/// Side of the floor or wall one texture covers, metres (a mesh's UVs are its metres over this).
pub const TILE_M: f32 = 2.0;
/// Parquet planks across one tile.
pub const PLANKS_PER_TILE: usize = 16;

/// A square texture, linear RGB, row-major from the top left.
#[derive(Clone, Debug, PartialEq)]
pub struct Painted {
    /// Side, pixels.
    pub size: usize,
    /// The pixels.
    pub rgb: Vec<[f32; 3]>,
}

impl Painted {
    fn paint(size: usize, mut f: impl FnMut(usize, usize) -> [f32; 3]) -> Self {
        Self { size, rgb: (0..size * size).map(|i| f(i % size, i / size)).collect() }
    }

    /// The pixel at column `x`, row `y` (wrapping: the texture tiles).
    pub fn at(&self, x: usize, y: usize) -> [f32; 3] {
        self.rgb[(y % self.size) * self.size + x % self.size]
    }

    /// An sRGB image with every mip level (box-filtered in linear light) and a repeating, trilinear sampler.
    pub fn image(&self) -> Image {
        let mut data = Vec::new();
        let mut level = self.clone();
        let mut levels = 0;
        loop {
            data.extend(level.rgb.iter().flat_map(|p| {
                let [r, g, b] = p.map(|c| (linear_to_srgb(c) * 255.0).round() as u8);
                [r, g, b, 255]
            }));
            levels += 1;
            if level.size == 1 {
                break;
            }
            level = level.halved();
        }
        let size = u32::try_from(self.size).unwrap_or(1);
        // `Image::new` checks the data against the top level alone; the mip chain follows it.
        let mut image = Image::new_uninit(
            Extent3d { width: size, height: size, depth_or_array_layers: 1 },
            TextureDimension::D2,
            TextureFormat::Rgba8UnormSrgb,
            RenderAssetUsages::RENDER_WORLD,
        );
        image.data = Some(data);
        image.texture_descriptor.mip_level_count = levels;
        image.sampler = ImageSampler::Descriptor(ImageSamplerDescriptor {
            address_mode_u: ImageAddressMode::Repeat,
            address_mode_v: ImageAddressMode::Repeat,
            ..ImageSamplerDescriptor::linear()
        });
        image
    }

    /// The next mip level: each pixel the mean of a 2×2 block.
    fn halved(&self) -> Self {
        Self::paint((self.size / 2).max(1), |x, y| {
            let block = [
                self.at(2 * x, 2 * y),
                self.at(2 * x + 1, 2 * y),
                self.at(2 * x, 2 * y + 1),
                self.at(2 * x + 1, 2 * y + 1),
            ];
            [0, 1, 2].map(|c| block.iter().map(|p| p[c]).sum::<f32>() * 0.25)
        })
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// A hash of two lattice coordinates and a seed to [0, 1).
fn hash(x: i64, y: i64, seed: u64) -> f32 {
    let mut h = seed ^ (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Smooth value noise in [0, 1) at (`u`, `v`) on a lattice of `period` cells that wraps (so it tiles).
fn noise(u: f32, v: f32, period: i64, seed: u64) -> f32 {
    let (x0, y0) = (u.floor(), v.floor());
    let (fx, fy) = (u - x0, v - y0);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let corner =
        |dx: i64, dy: i64| hash((x0 as i64 + dx).rem_euclid(period), (y0 as i64 + dy).rem_euclid(period), seed);
    let top = corner(0, 0) + (corner(1, 0) - corner(0, 0)) * sx;
    let bottom = corner(0, 1) + (corner(1, 1) - corner(0, 1)) * sx;
    top + (bottom - top) * sy
}

/// Four octaves of [`noise`] over the unit square (`u`, `v` in [0, 1)), tiling, mean about 0.5.
fn fractal(u: f32, v: f32, base: i64, seed: u64) -> f32 {
    (0..4)
        .map(|o| noise(u * (base << o) as f32, v * (base << o) as f32, base << o, seed + o as u64) / (1 << o) as f32)
        .sum::<f32>()
        / 1.875
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * t)
}

fn scale(a: [f32; 3], k: f32) -> [f32; 3] {
    a.map(|c| c * k)
}

/// Oak parquet: [`PLANKS_PER_TILE`] planks across, each half a tile long with staggered joints, each
/// plank its own tone, a fine grain along it and dark seams between.
pub fn parquet(size: usize) -> Painted {
    let oak = [0.30, 0.16, 0.07];
    let plank_px = size as f32 / PLANKS_PER_TILE as f32;
    Painted::paint(size, |x, y| {
        let (u, v) = (x as f32 / size as f32, y as f32 / size as f32);
        let column = (x as f32 / plank_px) as i64;
        let joint = hash(column, 0, 7) * 0.5;
        let along = (v - joint).rem_euclid(1.0);
        let plank = (along * 2.0) as i64; // two planks per column per tile
        let tone = 0.75 + 0.5 * hash(column, plank, 11);
        let grain = fractal(u * 0.25, v * 4.0, 4, 3 + column as u64);
        let streak = 0.85 + 0.3 * (0.5 + 0.5 * ((u * size as f32 * 0.9 + grain * 9.0).sin()));
        let across = x as f32 % plank_px;
        let seam = across < 1.0 || (along * 2.0).fract() * size as f32 * 0.5 < 1.0;
        if seam { scale(oak, 0.25) } else { scale(oak, tone * streak) }
    })
}

/// Painted plaster: a deep gallery red with a faint, soft mottling.
pub fn plaster(size: usize) -> Painted {
    let paint = [0.25, 0.045, 0.04];
    Painted::paint(size, |x, y| {
        let n = fractal(x as f32 / size as f32, y as f32 / size as f32, 8, 21);
        scale(paint, 0.85 + 0.3 * n)
    })
}

/// White marble with grey veins.
pub fn marble(size: usize) -> Painted {
    let (white, vein) = ([0.80, 0.79, 0.76], [0.22, 0.22, 0.24]);
    Painted::paint(size, |x, y| {
        let (u, v) = (x as f32 / size as f32, y as f32 / size as f32);
        let turbulence = fractal(u, v, 4, 31);
        let wave = ((u + v) * std::f32::consts::TAU * 2.0 + turbulence * 9.0).sin();
        let veins = (1.0 - wave.abs()).powi(12);
        mix(scale(white, 0.92 + 0.16 * fractal(u, v, 16, 37)), vein, veins * 0.8)
    })
}

/// Scales a mesh's first UV set so one unit of UV is [`TILE_M`] metres on a face `size` metres across
/// (its u along x or its longer side, v along the other): textures keep their scale on every floor and wall.
pub fn tile_uvs(mut mesh: Mesh, size: Vec2) -> Mesh {
    if let Some(bevy::mesh::VertexAttributeValues::Float32x2(uvs)) = mesh.attribute_mut(Mesh::ATTRIBUTE_UV_0) {
        for uv in uvs {
            *uv = [uv[0] * size.x / TILE_M, uv[1] * size.y / TILE_M];
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn luma(p: [f32; 3]) -> f32 {
        0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
    }

    fn spread(t: &Painted) -> (f32, f32) {
        let l: Vec<f32> = t.rgb.iter().map(|p| luma(*p)).collect();
        let mean = l.iter().sum::<f32>() / l.len() as f32;
        (mean, (l.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / l.len() as f32).sqrt() / mean)
    }

    /// The largest step across a tile's edge compared with the largest step inside it: a texture that
    /// tiles has no seam where it repeats.
    fn edge_step(t: &Painted, edge: impl Fn(usize) -> ((usize, usize), (usize, usize))) -> f32 {
        (0..t.size)
            .map(|i| {
                let ((ax, ay), (bx, by)) = edge(i);
                (luma(t.at(ax, ay)) - luma(t.at(bx, by))).abs()
            })
            .sum::<f32>()
            / t.size as f32
    }

    #[test]
    fn every_surface_is_textured_tiles_without_a_seam_and_is_made_the_same_every_time() {
        for (name, paint, variation) in [
            ("parquet", parquet as fn(usize) -> Painted, 0.15..0.8),
            ("plaster", plaster, 0.02..0.15),
            ("marble", marble, 0.05..0.5),
        ] {
            let t = paint(SIZE);
            assert_eq!(t, paint(SIZE), "{name} is the same every start-up");
            let (mean, cv) = spread(&t);
            assert!(variation.contains(&cv), "{name}: luma varies by {cv:.3} of its mean {mean:.3}");
            // Mean step between the last and first columns (rows) against the mean step between two
            // neighbouring columns (rows) inside: the same order, so no seam shows where the tile repeats.
            let s = t.size;
            let inside_x = edge_step(&t, |i| ((s / 2, i), (s / 2 + 1, i)));
            let wrap_x = edge_step(&t, |i| ((s - 1, i), (0, i)));
            let inside_y = edge_step(&t, |i| ((i, s / 2 - 7), (i, s / 2 - 6)));
            let wrap_y = edge_step(&t, |i| ((i, s - 1), (i, 0)));
            println!(
                "{name}: mean luma {mean:.3}, cv {cv:.3}, wrap x {wrap_x:.4} / {inside_x:.4}, y {wrap_y:.4} / {inside_y:.4}"
            );
            assert!(wrap_x <= 3.0 * inside_x.max(0.01 * mean), "{name} shows a seam at its left/right edge");
            assert!(wrap_y <= 3.0 * inside_y.max(0.01 * mean), "{name} shows a seam at its top/bottom edge");
        }
    }

    #[test]
    fn parquet_planks_differ_from_each_other_and_are_parted_by_dark_seams() {
        let t = parquet(SIZE);
        let plank_px = SIZE / PLANKS_PER_TILE;
        let tones: Vec<f32> = (0..PLANKS_PER_TILE)
            .map(|c| (0..SIZE).map(|y| luma(t.at(c * plank_px + plank_px / 2, y))).sum::<f32>() / SIZE as f32)
            .collect();
        let (lo, hi) = tones.iter().fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
        assert!(hi > 1.2 * lo, "planks have their own tones: {tones:?}");
        let seam = luma(t.at(plank_px, 3));
        assert!(seam < 0.5 * lo, "the seam between planks is dark: {seam} against planks from {lo}");
    }

    #[test]
    fn the_image_has_every_mip_level_in_srgb_and_repeats() {
        let image = plaster(SIZE).image();
        assert_eq!(image.texture_descriptor.mip_level_count, 9, "256, 128, ..., 1");
        let texels: usize = (0..9).map(|l| (SIZE >> l) * (SIZE >> l)).sum();
        assert_eq!(image.data.as_ref().map(Vec::len), Some(texels * 4));
        assert_eq!(image.texture_descriptor.format, TextureFormat::Rgba8UnormSrgb);
        let ImageSampler::Descriptor(sampler) = &image.sampler else { panic!("a sampler of its own") };
        assert_eq!(
            (sampler.address_mode_u, sampler.address_mode_v),
            (ImageAddressMode::Repeat, ImageAddressMode::Repeat)
        );
        // The 1×1 level is the texture's mean colour (in linear light).
        let data = image.data.as_ref().expect("data");
        let last = &data[data.len() - 4..];
        let mean = plaster(SIZE).rgb.iter().fold([0.0f32; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
        let expected = (linear_to_srgb(mean[0] / (SIZE * SIZE) as f32) * 255.0).round() as i32;
        assert!((i32::from(last[0]) - expected).abs() <= 1, "{} vs {expected}", last[0]);
    }

    #[test]
    fn a_floor_keeps_its_texture_scale_whatever_its_size() {
        let mesh = tile_uvs(Plane3d::default().mesh().size(8.0, 6.0).build(), Vec2::new(8.0, 6.0));
        let Some(bevy::mesh::VertexAttributeValues::Float32x2(uvs)) = mesh.attribute(Mesh::ATTRIBUTE_UV_0) else {
            panic!("UVs")
        };
        let (u, v) = uvs.iter().fold((0.0f32, 0.0f32), |(u, v), p| (u.max(p[0]), v.max(p[1])));
        assert_eq!((u, v), (8.0 / TILE_M, 6.0 / TILE_M), "one UV unit per {TILE_M} m");
    }
}
