//! A kira effect that places a mono track around the listener: HRTF convolution (the `hrtf` crate with
//! the spherical-head sphere of [`super::hrir`]) or, as a fallback, a plain interaural time and level
//! difference; both with inverse-distance roll-off.
//!
//! You need this module to make a sound come from somewhere. The game thread moves the source through
//! a [`BinauralHandle`] (latest placement through a triple buffer); the audio thread never waits. All
//! buffers are sized in `init`, so processing does not allocate.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use kira::Frame;
use kira::effect::{Effect, EffectBuilder};
use kira::info::Info;

use super::hrir::{HEAD_RADIUS_M, SPEED_OF_SOUND_M_PER_S, ear_delay_s};

/// Distance at which a source plays at full level, m.
pub const REFERENCE_DISTANCE_M: f32 = 1.0;
/// Sources farther than this are silent, m.
pub const MAX_DISTANCE_M: f32 = 60.0;
/// Samples per HRTF block.
const BLOCK: usize = 128;

/// Where a source is relative to the listener.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Offset from the listener's head in the listener's frame (+x right, +y up, −z ahead), m.
    pub offset: Vec3,
}

impl Placement {
    /// Unit direction to the source (ahead when the source is at the head).
    pub fn direction(&self) -> Vec3 {
        self.offset.try_normalize().unwrap_or(Vec3::NEG_Z)
    }

    /// Gain from distance: 1 within [`REFERENCE_DISTANCE_M`], then inverse distance; 0 past [`MAX_DISTANCE_M`].
    pub fn distance_gain(&self) -> f32 {
        let d = self.offset.length();
        if d > MAX_DISTANCE_M { 0.0 } else { (REFERENCE_DISTANCE_M / d.max(REFERENCE_DISTANCE_M)).min(1.0) }
    }
}

/// How the effects render: convolution with an HRIR sphere while HRTF is on (and a sphere is there),
/// interaural time and level differences otherwise. Clones share the switch, so one
/// [`Spatializer::set_hrtf`] turns every voice over at its next block.
#[derive(Clone)]
pub struct Spatializer {
    sphere: Option<Arc<hrtf::HrirSphere>>,
    hrtf_on: Arc<AtomicBool>,
}

impl Spatializer {
    /// Renders with `sphere`, HRTF on at first when `on`.
    pub fn hrtf(sphere: hrtf::HrirSphere, on: bool) -> Self {
        Self { sphere: Some(Arc::new(sphere)), hrtf_on: Arc::new(AtomicBool::new(on)) }
    }

    /// Time and level differences only (no sphere: HRTF cannot be turned on).
    pub fn time_level() -> Self {
        Self { sphere: None, hrtf_on: Arc::new(AtomicBool::new(false)) }
    }

    /// Turns HRTF on or off for every voice (no effect without a sphere).
    pub fn set_hrtf(&self, on: bool) {
        self.hrtf_on.store(on, Ordering::Relaxed);
    }

    /// True when the voices render with the HRTF.
    pub fn uses_hrtf(&self) -> bool {
        self.sphere.is_some() && self.hrtf_on.load(Ordering::Relaxed)
    }
}

/// Builds a [`BinauralHandle`]'s effect.
pub struct BinauralBuilder {
    spatializer: Spatializer,
    placement: Placement,
}

impl BinauralBuilder {
    /// An effect rendering with `spatializer`, starting at `placement`.
    pub fn new(spatializer: Spatializer, placement: Placement) -> Self {
        Self { spatializer, placement }
    }
}

/// Moves a binaural source.
pub struct BinauralHandle {
    input: triple_buffer::Input<Placement>,
}

impl BinauralHandle {
    /// Places the source.
    pub fn set(&mut self, placement: Placement) {
        self.input.write(placement);
    }
}

impl EffectBuilder for BinauralBuilder {
    type Handle = BinauralHandle;

    fn build(self) -> (Box<dyn Effect>, Self::Handle) {
        let (input, output) = triple_buffer::triple_buffer(&self.placement);
        let effect = BinauralEffect {
            spatializer: self.spatializer,
            processor: None,
            placement: output,
            current: self.placement,
            previous: self.placement,
            fifo_in: VecDeque::new(),
            fifo_out: VecDeque::new(),
            block_in: Vec::new(),
            block_out: Vec::new(),
            prev_left: Vec::new(),
            prev_right: Vec::new(),
            delay_line: VecDeque::new(),
            sample_rate: 48_000,
        };
        (Box::new(effect), BinauralHandle { input })
    }
}

struct BinauralEffect {
    spatializer: Spatializer,
    processor: Option<hrtf::HrtfProcessor>,
    placement: triple_buffer::Output<Placement>,
    current: Placement,
    previous: Placement,
    fifo_in: VecDeque<f32>,
    fifo_out: VecDeque<(f32, f32)>,
    block_in: Vec<f32>,
    block_out: Vec<(f32, f32)>,
    prev_left: Vec<f32>,
    prev_right: Vec<f32>,
    delay_line: VecDeque<f32>,
    sample_rate: u32,
}

impl Effect for BinauralEffect {
    fn init(&mut self, sample_rate: u32, internal_buffer_size: usize) {
        self.sample_rate = sample_rate;
        let room = internal_buffer_size.max(BLOCK) * 4;
        self.fifo_in = VecDeque::with_capacity(room);
        self.fifo_out = VecDeque::with_capacity(room);
        self.block_in = vec![0.0; BLOCK];
        self.block_out = vec![(0.0, 0.0); BLOCK];
        self.prev_left = Vec::with_capacity(4 * BLOCK);
        self.prev_right = Vec::with_capacity(4 * BLOCK);
        // Longest interaural delay plus the common one, with margin.
        let max_delay = ((2.0 * HEAD_RADIUS_M / SPEED_OF_SOUND_M_PER_S + 0.002) * sample_rate as f32) as usize + 2;
        self.delay_line = VecDeque::from(vec![0.0; max_delay]);
        if let Some(sphere) = &self.spatializer.sphere {
            self.processor = Some(hrtf::HrtfProcessor::new((**sphere).clone(), 1, BLOCK));
        }
    }

    fn on_start_processing(&mut self) {
        self.current = *self.placement.read();
    }

    fn process(&mut self, input: &mut [Frame], _dt: f64, _info: &Info) {
        let hrtf_on = self.spatializer.hrtf_on.load(Ordering::Relaxed);
        if !hrtf_on && !self.fifo_in.is_empty() {
            // Switched off: what the convolution still held is dropped, not played late.
            self.fifo_in.clear();
            self.fifo_out.clear();
        }
        match self.processor.as_mut().filter(|_| hrtf_on) {
            Some(processor) => {
                for f in input.iter() {
                    self.fifo_in.push_back(0.5 * (f.left + f.right));
                }
                while self.fifo_in.len() >= BLOCK {
                    for (dst, src) in self.block_in.iter_mut().zip(self.fifo_in.drain(..BLOCK)) {
                        *dst = src;
                    }
                    self.block_out.fill((0.0, 0.0));
                    let dir = |p: &Placement| {
                        let d = p.direction();
                        hrtf::Vec3::new(d.x, d.y, d.z)
                    };
                    processor.process_samples(hrtf::HrtfContext {
                        source: &self.block_in,
                        output: &mut self.block_out,
                        new_sample_vector: dir(&self.current),
                        prev_sample_vector: dir(&self.previous),
                        prev_left_samples: &mut self.prev_left,
                        prev_right_samples: &mut self.prev_right,
                        new_distance_gain: self.current.distance_gain(),
                        prev_distance_gain: self.previous.distance_gain(),
                    });
                    self.previous = self.current;
                    self.fifo_out.extend(self.block_out.iter().copied());
                }
                for f in input.iter_mut() {
                    let (l, r) = self.fifo_out.pop_front().unwrap_or((0.0, 0.0));
                    *f = Frame { left: l, right: r };
                }
            }
            None => self.time_level(input),
        }
    }
}

impl BinauralEffect {
    /// Interaural time difference from the spherical head, level difference from a simple cardioid
    /// per ear (1 facing the ear, 0.35 opposite).
    fn time_level(&mut self, input: &mut [Frame]) {
        let dir = self.current.direction();
        let gain = self.current.distance_gain();
        let fs = self.sample_rate as f32;
        let ears = [Vec3::NEG_X, Vec3::X].map(|ear| {
            let level = 0.35 + 0.65 * (1.0 + ear.dot(dir)) / 2.0;
            (ear_delay_s(ear, dir) * fs, level * gain)
        });
        let len = self.delay_line.len();
        for f in input.iter_mut() {
            self.delay_line.pop_back();
            self.delay_line.push_front(0.5 * (f.left + f.right));
            let tap = |d: f32| {
                let d = d.clamp(0.0, (len - 2) as f32);
                let (i, frac) = (d.floor() as usize, d.fract());
                self.delay_line[i] * (1.0 - frac) + self.delay_line[i + 1] * frac
            };
            *f = Frame { left: tap(ears[0].0) * ears[0].1, right: tap(ears[1].0) * ears[1].1 };
        }
    }
}
