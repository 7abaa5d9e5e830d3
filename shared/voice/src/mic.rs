//! Where the voice comes from: the system's microphone through cpal (feature `mic`), or a WAV file that
//! stands in for it (`--mic-wav FILE`: each transmission says the file from its start, then silence).
//!
//! You need this module to add a voice source. Every source yields 48 kHz mono; the caller's clock
//! (`now_s`) paces the file, the sound card paces the microphone. The microphone's callback only copies
//! samples into a ring buffer sized up front; resampling happens on the game thread.

use std::path::Path;

use crate::{VOICE_SAMPLE_RATE, VoiceError};

/// Resamples a whole mono clip to [`VOICE_SAMPLE_RATE`].
pub fn resample_clip(samples: &[f32], from_hz: u32) -> Result<Vec<f32>, VoiceError> {
    use rubato::Resampler as _;
    use rubato::audioadapter_buffers::direct::SequentialSlice;
    if from_hz == VOICE_SAMPLE_RATE || samples.is_empty() {
        return Ok(samples.to_vec());
    }
    let bad = |e: String| VoiceError::Codec(format!("resampling from {from_hz} Hz: {e}"));
    let ratio = f64::from(VOICE_SAMPLE_RATE) / f64::from(from_hz);
    let mut resampler =
        rubato::Async::<f32>::new_poly(ratio, 1.0, rubato::PolynomialDegree::Cubic, 1024, 1, rubato::FixedAsync::Input)
            .map_err(|e| bad(e.to_string()))?;
    let input = SequentialSlice::new(samples, 1, samples.len()).map_err(|e| bad(e.to_string()))?;
    let mut out = vec![0.0; resampler.process_all_needed_output_len(samples.len())];
    let capacity = out.len();
    let mut output = SequentialSlice::new_mut(&mut out, 1, capacity).map_err(|e| bad(e.to_string()))?;
    let (_, n) =
        resampler.process_all_into_buffer(&input, &mut output, samples.len(), None).map_err(|e| bad(e.to_string()))?;
    out.truncate(n);
    Ok(out)
}

/// Reads a WAV file (PCM 8–32 bit or float, any rate, any channels) as 48 kHz mono.
pub fn read_wav(path: &Path) -> Result<Vec<f32>, VoiceError> {
    let bad = |why: String| VoiceError::MicFile { path: path.to_owned(), why };
    let mut reader = hound::WavReader::open(path).map_err(|e| bad(e.to_string()))?;
    let spec = reader.spec();
    let channels = usize::from(spec.channels.max(1));
    let interleaved: Vec<f32> = match spec.sample_format {
        hound::SampleFormat::Float => reader.samples::<f32>().collect::<Result<_, _>>(),
        hound::SampleFormat::Int => {
            let scale = 1.0 / (1u64 << (spec.bits_per_sample.clamp(1, 32) - 1)) as f32;
            reader.samples::<i32>().map(|s| s.map(|v| v as f32 * scale)).collect::<Result<_, _>>()
        }
    }
    .map_err(|e| bad(e.to_string()))?;
    let mono: Vec<f32> = interleaved.chunks(channels).map(|c| c.iter().sum::<f32>() / channels as f32).collect();
    if mono.is_empty() {
        return Err(bad("it holds no sound".into()));
    }
    resample_clip(&mono, spec.sample_rate).map_err(|e| bad(e.to_string()))
}

/// A WAV file as the microphone: [`WavMic::start`] (push-to-talk down) plays it from its start, paced by
/// the caller's clock; past its end the microphone hears silence.
#[derive(Clone, Debug)]
pub struct WavMic {
    samples: Vec<f32>,
    started_s: Option<f64>,
    /// Samples handed out since the start.
    given: usize,
}

impl WavMic {
    /// The file at `path`.
    pub fn open(path: &Path) -> Result<Self, VoiceError> {
        Ok(Self::from_samples(read_wav(path)?))
    }

    /// 48 kHz mono samples as the microphone.
    pub fn from_samples(samples: Vec<f32>) -> Self {
        Self { samples, started_s: None, given: 0 }
    }

    /// The file's length, seconds.
    pub fn duration_s(&self) -> f64 {
        self.samples.len() as f64 / f64::from(VOICE_SAMPLE_RATE)
    }

    /// Starts the file again at `now_s`.
    pub fn start(&mut self, now_s: f64) {
        self.started_s = Some(now_s);
        self.given = 0;
    }

    /// True once the whole file has been heard since the last start.
    pub fn said(&self) -> bool {
        self.started_s.is_some() && self.given >= self.samples.len()
    }

    /// Appends what the microphone heard up to `now_s` to `out`.
    pub fn read(&mut self, now_s: f64, out: &mut Vec<f32>) {
        let Some(t0) = self.started_s else { return };
        let due = ((now_s - t0).max(0.0) * f64::from(VOICE_SAMPLE_RATE)).round() as usize;
        if due <= self.given {
            return;
        }
        let from_file = self.samples.get(self.given..due.min(self.samples.len())).unwrap_or(&[]);
        out.extend_from_slice(from_file);
        out.resize(out.len() + (due - self.given - from_file.len()), 0.0);
        self.given = due;
    }
}

/// The system's default microphone (feature `mic`).
#[cfg(feature = "mic")]
pub struct CpalMic {
    ring: rtrb::Consumer<f32>,
    rate: u32,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
    pending: Vec<f32>,
}

#[cfg(feature = "mic")]
impl CpalMic {
    /// Opens the default input device; its stream lives on a thread of its own (a cpal stream may not
    /// move between threads).
    pub fn open() -> Result<Self, VoiceError> {
        use cpal::traits::{DeviceTrait, HostTrait, StreamTrait};
        use std::sync::atomic::{AtomicBool, Ordering};
        let (tx, rx) = std::sync::mpsc::channel();
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let stop_flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("microphone".into())
            .spawn(move || {
                let opened = (|| {
                    let device = cpal::default_host()
                        .default_input_device()
                        .ok_or_else(|| "the system has no input device".to_owned())?;
                    // 48 kHz as it is, if the device offers it (no resampling); else its default.
                    let at_48k = device.supported_input_configs().ok().and_then(|mut configs| {
                        configs.find_map(|c| {
                            let fmt = c.sample_format();
                            let usable = matches!(fmt, cpal::SampleFormat::F32 | cpal::SampleFormat::I16);
                            if usable { c.try_with_sample_rate(VOICE_SAMPLE_RATE) } else { None }
                        })
                    });
                    let config = match at_48k {
                        Some(c) => c,
                        None => device.default_input_config().map_err(|e| e.to_string())?,
                    };
                    let channels = usize::from(config.channels().max(1));
                    let rate = config.sample_rate();
                    // Two seconds of room: the game thread drains it every frame.
                    let (mut producer, consumer) = rtrb::RingBuffer::<f32>::new(rate as usize * 2);
                    let warn = |e: cpal::Error| log::warn!("microphone: {e}");
                    let stream = match config.sample_format() {
                        cpal::SampleFormat::F32 => device.build_input_stream::<f32, _, _>(
                            config.config(),
                            move |data: &[f32], _| {
                                for frame in data.chunks(channels) {
                                    let _ = producer.push(frame.iter().sum::<f32>() / channels as f32);
                                }
                            },
                            warn,
                            None,
                        ),
                        cpal::SampleFormat::I16 => device.build_input_stream::<i16, _, _>(
                            config.config(),
                            move |data: &[i16], _| {
                                for frame in data.chunks(channels) {
                                    let sum: f32 = frame.iter().map(|s| f32::from(*s) / 32768.0).sum();
                                    let _ = producer.push(sum / channels as f32);
                                }
                            },
                            warn,
                            None,
                        ),
                        other => return Err(format!("the input device gives {other} samples, not f32 or i16")),
                    }
                    .map_err(|e| e.to_string())?;
                    stream.play().map_err(|e| e.to_string())?;
                    Ok::<_, String>((stream, consumer, rate))
                })();
                match opened {
                    Ok((stream, consumer, rate)) => {
                        let _ = tx.send(Ok((consumer, rate)));
                        while !stop_flag.load(Ordering::Acquire) {
                            std::thread::sleep(std::time::Duration::from_millis(50));
                        }
                        drop(stream);
                    }
                    Err(e) => {
                        let _ = tx.send(Err(e));
                    }
                }
            })
            .map_err(|e| VoiceError::NoMicrophone(e.to_string()))?;
        let (ring, rate) = rx
            .recv_timeout(std::time::Duration::from_secs(5))
            .map_err(|_| VoiceError::NoMicrophone("the input device did not open within 5 s".into()))?
            .map_err(VoiceError::NoMicrophone)?;
        Ok(Self { ring, rate, stop, thread: Some(thread), pending: Vec::with_capacity(rate as usize) })
    }

    /// Appends what the microphone heard since the last call, at 48 kHz, to `out`.
    pub fn read(&mut self, out: &mut Vec<f32>) {
        self.pending.clear();
        while let Ok(s) = self.ring.pop() {
            self.pending.push(s);
        }
        match resample_clip(&self.pending, self.rate) {
            Ok(s) => out.extend(s),
            Err(e) => log::warn!("microphone: {e}"),
        }
    }
}

#[cfg(feature = "mic")]
impl Drop for CpalMic {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The microphone in use.
pub enum Microphone {
    /// A WAV file.
    Wav(WavMic),
    /// The system's microphone.
    #[cfg(feature = "mic")]
    Device(CpalMic),
}

impl Microphone {
    /// Push-to-talk went down at `now_s` (a file starts over).
    pub fn start(&mut self, now_s: f64) {
        match self {
            Microphone::Wav(w) => w.start(now_s),
            #[cfg(feature = "mic")]
            Microphone::Device(d) => {
                // What it heard before the key went down is not part of the transmission.
                let mut discard = Vec::new();
                d.read(&mut discard);
            }
        }
    }

    /// True when a file has been said whole (a device never is).
    pub fn said(&self) -> bool {
        match self {
            Microphone::Wav(w) => w.said(),
            #[cfg(feature = "mic")]
            Microphone::Device(_) => false,
        }
    }

    /// Appends what it heard up to `now_s` to `out` (48 kHz mono).
    pub fn read(&mut self, now_s: f64, out: &mut Vec<f32>) {
        match self {
            Microphone::Wav(w) => w.read(now_s, out),
            #[cfg(feature = "mic")]
            Microphone::Device(d) => {
                let _ = now_s;
                d.read(out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wav_mic_says_its_file_from_the_start_at_the_callers_pace_then_silence() {
        let mut mic = WavMic::from_samples(vec![0.5; 4800]); // 100 ms
        let mut out = Vec::new();
        mic.read(1.0, &mut out);
        assert!(out.is_empty(), "nothing before push-to-talk");
        mic.start(1.0);
        mic.read(1.05, &mut out);
        assert_eq!(out.len(), 2400);
        mic.read(1.2, &mut out);
        assert_eq!(out.len(), 9600);
        assert!(out[..4800].iter().all(|s| *s == 0.5) && out[4800..].iter().all(|s| *s == 0.0));
        mic.start(2.0);
        out.clear();
        mic.read(2.01, &mut out);
        assert_eq!((out.len(), out[0]), (480, 0.5), "a new transmission starts the file over");
    }

    #[test]
    fn a_clip_is_resampled_to_48_khz_keeping_its_length_and_pitch() {
        let from = 22_050;
        let tone: Vec<f32> =
            (0..from).map(|i| (std::f32::consts::TAU * 440.0 * i as f32 / from as f32).sin() * 0.5).collect();
        let out = resample_clip(&tone, from).expect("resamples");
        assert!((out.len() as i64 - 48_000).abs() < 100, "{} samples for one second", out.len());
        let crossings = out.windows(2).filter(|w| w[0] < 0.0 && w[1] >= 0.0).count();
        assert!((438..=442).contains(&crossings), "{crossings} cycles");
    }

    #[test]
    fn a_file_that_is_no_wav_says_which_file_and_why() {
        let path = std::env::temp_dir().join(format!("phantom-mic-{}.wav", std::process::id()));
        std::fs::write(&path, b"not a wav").expect("writes");
        let err = WavMic::open(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");
        let missing = WavMic::open(Path::new("/nonexistent/mic.wav")).unwrap_err().to_string();
        assert!(missing.contains("/nonexistent/mic.wav"), "{missing}");
    }
}
