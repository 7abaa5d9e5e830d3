//! A small software ray tracer that draws a tree's spheres (like the IST paper's packing figures).
//!
//! You need this module to look at a packing: `collette render` calls it. The left panel shows the
//! whole packing, the right panel the same view cut in half, so the inner spheres are visible.

use crate::partitioning::InnerSphereTree;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::TAU;
use std::path::Path;

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes.
    pub pixels: Vec<u8>,
}

impl RgbImage {
    /// Writes the image as a PNG file.
    pub fn write_png(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        let file = std::io::BufWriter::new(std::fs::File::create(path)?);
        let mut enc = png::Encoder::new(file, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(&self.pixels).map_err(std::io::Error::other)?;
        w.finish().map_err(std::io::Error::other)
    }
}

/// Renders two `panel`×`panel` views side by side (whole, and cut at the centre plane facing the camera).
/// `yaw` and `pitch` (radians) turn the camera around the tree's centre.
pub fn render_packing(tree: &InnerSphereTree, panel: u32, yaw: f32, pitch: f32) -> RgbImage {
    let root = tree.root().bound;
    let forward = -Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos());
    let right = forward.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
    let up = right.cross(forward);
    let eye = root.center - forward * root.radius * 4.0;
    let half_fov = (root.radius * 1.1 / (root.radius * 4.0)).atan();
    let light = (-forward + up * 0.8 + right * 0.5).normalize();
    let width = panel * 2;
    let mut pixels = vec![0u8; (width * panel * 3) as usize];
    pixels.par_chunks_mut((width * 3) as usize).enumerate().for_each_init(Vec::new, |stack, (y, row)| {
        for x in 0..width {
            let cut = x >= panel;
            let px = (x % panel) as f32 + 0.5;
            let (u, v) = ((px / panel as f32) * 2.0 - 1.0, 1.0 - ((y as f32 + 0.5) / panel as f32) * 2.0);
            let dir = (forward + (right * u + up * v) * half_fov.tan()).normalize();
            let color = match trace(tree, eye, dir, cut.then_some((root.center, forward)), stack) {
                Some((index, p, n)) => shade(index, p, n, light, dir),
                None => {
                    let g = 245.0 - 40.0 * ((y as f32) / panel as f32);
                    [g, g, g + 5.0]
                }
            };
            let o = (x * 3) as usize;
            for c in 0..3 {
                row[o + c] = color[c].clamp(0.0, 255.0) as u8;
            }
        }
    });
    RgbImage { width, height: panel, pixels }
}

/// Nearest sphere hit: (sphere index, point, normal). With a cut, spheres whose centre lies on the
/// camera's side of the plane (point, normal) are skipped.
fn trace(
    tree: &InnerSphereTree,
    o: Vec3,
    d: Vec3,
    cut: Option<(Vec3, Vec3)>,
    stack: &mut Vec<u32>,
) -> Option<(usize, Vec3, Vec3)> {
    let hit = |c: Vec3, r: f32| -> Option<f32> {
        let oc = o - c;
        let b = oc.dot(d);
        let disc = b * b - (oc.length_squared() - r * r);
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let t = -b - s;
        Some(if t > 0.0 { t } else { -b + s }).filter(|t| *t > 0.0)
    };
    let mut best: Option<(f32, usize)> = None;
    stack.clear();
    stack.push(0);
    while let Some(n) = stack.pop() {
        let node = &tree.nodes()[n as usize];
        match hit(node.bound.center, node.bound.radius) {
            Some(_) if node.bound.center.distance(o) <= node.bound.radius => {}
            Some(t) if best.is_none_or(|b| t - 2.0 * node.bound.radius < b.0) => {}
            _ => continue,
        }
        if node.leaf {
            for i in node.range() {
                let s = &tree.spheres()[i];
                if let Some((p, f)) = cut
                    && (s.center - p).dot(f) < 0.0
                {
                    continue;
                }
                if let Some(t) = hit(s.center, s.radius)
                    && best.is_none_or(|b| t < b.0)
                {
                    best = Some((t, i));
                }
            }
        } else {
            stack.extend(node.range().map(|c| c as u32));
        }
    }
    best.map(|(t, i)| {
        let p = o + d * t;
        (i, p, (p - tree.spheres()[i].center).normalize())
    })
}

fn shade(index: usize, _p: Vec3, n: Vec3, light: Vec3, dir: Vec3) -> [f32; 3] {
    // A stable pseudo-random hue per sphere, so neighbours are told apart.
    let h = (index as u32).wrapping_mul(2_654_435_761) as f32 / u32::MAX as f32;
    let base = Vec3::new(
        0.55 + 0.45 * (TAU * h).cos(),
        0.55 + 0.45 * (TAU * (h + 0.33)).cos(),
        0.55 + 0.45 * (TAU * (h + 0.67)).cos(),
    );
    let diffuse = n.dot(light).max(0.0);
    let spec = (2.0 * n.dot(light) * n - light).dot(-dir).max(0.0).powf(24.0);
    let c = base * (0.25 + 0.75 * diffuse) + Vec3::splat(0.35 * spec);
    [c.x * 255.0, c.y * 255.0, c.z * 255.0]
}
