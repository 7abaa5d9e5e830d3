//! Where the mixed audio goes: the sound card (feature `sound-card`), or memory.
//!
//! You need this module to hear the client, or to test what it plays: a [`Capture`] drives kira's
//! renderer by hand and hands back the stereo frames, so tests "listen" through numbers.

use std::sync::{Arc, Mutex};

use kira::backend::{Backend, Renderer};

/// The renderer a [`CaptureBackend`] was started with, shared with its [`Capture`].
type Slot = Arc<Mutex<Option<Renderer>>>;

/// A kira backend that renders only when asked (offline), into memory.
pub struct CaptureBackend {
    slot: Slot,
}

/// Settings of a [`CaptureBackend`].
#[derive(Clone)]
pub struct CaptureSettings {
    /// Sample rate, Hz (default 48 000).
    pub sample_rate: u32,
    slot: Slot,
}

impl CaptureSettings {
    /// Settings for a capture at `sample_rate`, and the handle that renders it.
    pub fn new(sample_rate: u32) -> (Self, Capture) {
        let slot: Slot = Arc::new(Mutex::new(None));
        (Self { sample_rate, slot: slot.clone() }, Capture { slot, sample_rate })
    }
}

impl Backend for CaptureBackend {
    type Settings = CaptureSettings;
    type Error = std::convert::Infallible;

    fn setup(settings: Self::Settings, _internal_buffer_size: usize) -> Result<(Self, u32), Self::Error> {
        Ok((Self { slot: settings.slot }, settings.sample_rate))
    }

    fn start(&mut self, renderer: Renderer) -> Result<(), Self::Error> {
        *self.slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(renderer);
        Ok(())
    }
}

/// Renders a [`CaptureBackend`]'s audio on demand.
#[derive(Clone)]
pub struct Capture {
    slot: Slot,
    sample_rate: u32,
}

impl Capture {
    /// The sample rate, Hz.
    pub fn sample_rate(&self) -> u32 {
        self.sample_rate
    }

    /// Renders the next `frames` stereo frames as (left, right); silence before the manager starts.
    pub fn render(&self, frames: usize) -> Vec<(f32, f32)> {
        let mut out = vec![0.0f32; frames * 2];
        if let Some(renderer) = self.slot.lock().unwrap_or_else(|p| p.into_inner()).as_mut() {
            // In blocks of 512 like a sound card would ask, so commands are picked up between blocks.
            for chunk in out.chunks_mut(1024) {
                renderer.on_start_processing();
                renderer.process(chunk, 2);
            }
        }
        out.chunks(2).map(|c| (c[0], c[1])).collect()
    }
}

/// Writes stereo frames as a 16-bit PCM WAV file.
pub fn write_wav(path: &std::path::Path, sample_rate: u32, frames: &[(f32, f32)]) -> std::io::Result<()> {
    let data_len = (frames.len() * 4) as u32;
    let mut bytes = Vec::with_capacity(44 + data_len as usize);
    bytes.extend_from_slice(b"RIFF");
    bytes.extend_from_slice(&(36 + data_len).to_le_bytes());
    bytes.extend_from_slice(b"WAVEfmt ");
    bytes.extend_from_slice(&16u32.to_le_bytes());
    bytes.extend_from_slice(&1u16.to_le_bytes()); // PCM
    bytes.extend_from_slice(&2u16.to_le_bytes()); // stereo
    bytes.extend_from_slice(&sample_rate.to_le_bytes());
    bytes.extend_from_slice(&(sample_rate * 4).to_le_bytes());
    bytes.extend_from_slice(&4u16.to_le_bytes());
    bytes.extend_from_slice(&16u16.to_le_bytes());
    bytes.extend_from_slice(b"data");
    bytes.extend_from_slice(&data_len.to_le_bytes());
    for (l, r) in frames {
        for s in [l, r] {
            bytes.extend_from_slice(&((s.clamp(-1.0, 1.0) * 32767.0) as i16).to_le_bytes());
        }
    }
    std::fs::write(path, bytes)
}
