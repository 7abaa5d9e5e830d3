//! The Haply Inverse3 through the Haply Inverse Service (its local WebSocket API), with the official
//! `haply` crate's message model.
//!
//! You need this module to drive an Inverse3: [`open`] connects to the service, takes the first
//! Inverse3 it lists, centres on where the player holds the grip still, and runs the exchange on an I/O
//! thread ([`crate::io::IoDevice`]): each state frame the service sends is merged by the crate
//! (`haply::state::update_state_on_message`) and handed to the haptic thread, and each is answered with
//! the newest force (the crate's `SetCursorForce` command in its `ServiceMsg`). [`probe`] lists what a
//! running service offers. The socket is ours, not the crate's `HaplyDevice`: its listener never leaves
//! its loop when the service closes the connection and spins a core, which a game must survive
//! (docs/decisions.md). Tested against a local service speaking the crate's types; never against
//! hardware.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use glam::Vec3;
use haply::device_model::{
    Command, Inverse3Device, ProfileConfig, ServiceMsg, SessionConfigure, TimestampedServiceData, Vec3D,
    VerseGripDuplicateMode,
};
use haptic_common::{DeviceState, ForceTorque, Pose};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

use crate::io::{IoDevice, IoThread};
use crate::timing::HapticClock;
use crate::{DeviceSpecs, HapticoError, Result};

/// Where the Haply Inverse Service listens for WebSocket clients by default.
pub const DEFAULT_URL: &str = "ws://localhost:10001/";
/// How long the service has to accept the connection.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(3);
/// How long the service has to list an Inverse3 once connected.
pub const FIRST_DEVICE_TIMEOUT: Duration = Duration::from_secs(3);
/// How long the grip is read, held still, to find the centre.
pub const CENTRING: Duration = Duration::from_millis(300);
/// How far the grip may wander while it is being centred, m.
pub const HOLD_STILL_M: f32 = 0.01;
/// Without a state frame for this long, the newest force is sent anyway (so that a service which
/// answers commands starts streaming).
const KEEPALIVE: Duration = Duration::from_millis(2);
/// A send that takes longer than this means the service stopped reading.
const SEND_TIMEOUT: Duration = Duration::from_millis(200);

type Socket = WebSocketStream<MaybeTlsStream<TcpStream>>;
type SharedState = Arc<tokio::sync::Mutex<TimestampedServiceData>>;

fn new_state() -> SharedState {
    Arc::new(tokio::sync::Mutex::new(TimestampedServiceData { data: Default::default(), timestamp: Instant::now() }))
}

/// Haply's frame (x right, y away from the player, z up; origin on the base plate) to ours (x right,
/// y up, z toward the player).
pub fn to_ours(v: Vec3D) -> Vec3 {
    Vec3::new(v.x, v.z, -v.y)
}

/// Ours to Haply's (the inverse of [`to_ours`]).
pub fn to_haply(v: Vec3) -> Vec3D {
    Vec3D { x: v.x, y: -v.z, z: v.y }
}

/// What the I/O thread saw, readable from any thread.
#[derive(Debug, Default)]
pub struct HaplyStatus {
    frames: AtomicU64,
    commands: AtomicU64,
    disconnected: AtomicBool,
    calibrated: AtomicBool,
    ready: AtomicBool,
    rtt_count: AtomicU64,
    rtt_sum_us: AtomicU64,
    rtt_max_us: AtomicU64,
}

impl HaplyStatus {
    /// State frames received for the Inverse3.
    pub fn frames(&self) -> u64 {
        self.frames.load(Ordering::Relaxed)
    }
    /// Force commands sent.
    pub fn commands(&self) -> u64 {
        self.commands.load(Ordering::Relaxed)
    }
    /// True once the service closed the connection or stopped reading: no force reaches the device.
    pub fn disconnected(&self) -> bool {
        self.disconnected.load(Ordering::Acquire)
    }
    /// What the service last said of the device: calibrated, ready.
    pub fn calibrated_ready(&self) -> (bool, bool) {
        (self.calibrated.load(Ordering::Relaxed), self.ready.load(Ordering::Relaxed))
    }
    /// Round trips measured (a new force sent until the service reports it as the device's force), and
    /// their mean and largest, µs.
    pub fn round_trips(&self) -> (u64, Option<f64>, u64) {
        let n = self.rtt_count.load(Ordering::Relaxed);
        let mean = (n > 0).then(|| self.rtt_sum_us.load(Ordering::Relaxed) as f64 / n as f64);
        (n, mean, self.rtt_max_us.load(Ordering::Relaxed))
    }
    fn round_trip(&self, us: u64) {
        self.rtt_count.fetch_add(1, Ordering::Relaxed);
        self.rtt_sum_us.fetch_add(us, Ordering::Relaxed);
        self.rtt_max_us.fetch_max(us, Ordering::Relaxed);
    }
    fn saw(&self, d: &Inverse3Device) {
        self.frames.fetch_add(1, Ordering::Relaxed);
        self.calibrated.store(d.status.calibrated, Ordering::Relaxed);
        self.ready.store(d.status.ready, Ordering::Relaxed);
    }
}

/// An Inverse3 a running service lists.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Listed {
    /// The service's id of the device.
    pub device_id: String,
    /// Whether the service says it is calibrated.
    pub calibrated: bool,
    /// Whether the service says it is ready.
    pub ready: bool,
}

/// Lists the Inverse3 devices the service at `url` offers (connecting for at most `wait` twice: once to
/// connect, once for the first frame).
pub fn probe(url: &str, wait: Duration) -> Result<Vec<Listed>> {
    let rt = runtime()?;
    rt.block_on(async {
        let mut ws = connect(url, wait).await?;
        let state = new_state();
        hello(&mut ws).await?;
        let found = first_frame(&mut ws, &state, wait).await;
        let _ = ws.close(None).await;
        found?;
        let data = state.lock().await;
        Ok(data
            .data
            .inverse3
            .iter()
            .map(|d| Listed { device_id: d.device_id.clone(), calibrated: d.status.calibrated, ready: d.status.ready })
            .collect())
    })
}

/// Opens the first Inverse3 of the service at `url`: connects (failing within [`CONNECT_TIMEOUT`] when
/// no service answers), waits for it to be listed, reads the grip for [`CENTRING`] (it must be held
/// still) and puts that point at `centre_at` in the device frame, then starts the I/O thread. `specs`
/// are the device's limits for the safety layer.
pub fn open(url: &str, specs: DeviceSpecs, centre_at: Vec3) -> Result<(IoDevice, Arc<HaplyStatus>)> {
    let rt = runtime()?;
    let state = new_state();
    let status = Arc::new(HaplyStatus::default());
    let (ws, device_id, centre) = rt.block_on(async {
        let mut ws = connect(url, CONNECT_TIMEOUT).await?;
        hello(&mut ws).await?;
        let device_id = first_frame(&mut ws, &state, FIRST_DEVICE_TIMEOUT).await?;
        let centre = centre_on_the_grip(&mut ws, &state, &device_id).await?;
        Ok::<_, HapticoError>((ws, device_id, centre))
    })?;
    let clock = HapticClock::new();
    let map = Map { centre, centre_at };
    let first = rt.block_on(async {
        let data = state.lock().await;
        let d = data.data.inverse3.iter().find(|d| d.device_id == device_id).cloned().unwrap_or_default();
        map.state(&d, clock.now_us())
    });
    let thread_status = status.clone();
    let io = IoDevice::with_loop(specs, first, clock, "haply-io", move |io| {
        rt.block_on(exchange(ws, io, state, device_id, map, thread_status));
    })?;
    Ok((io, status))
}

fn runtime() -> Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| HapticoError::InvalidConfig(format!("cannot start the Haply I/O runtime: {e}")))
}

fn no_service(url: &str, why: impl std::fmt::Display) -> HapticoError {
    HapticoError::NoDevice {
        wanted: format!("Haply Inverse Service at {url}"),
        hint: format!(
            "{why}; start the service (Linux: systemctl start haply-inverse-service) or give its address with \
             --device haply:ws://HOST:PORT/"
        ),
    }
}

async fn connect(url: &str, wait: Duration) -> Result<Socket> {
    match tokio::time::timeout(wait, tokio_tungstenite::connect_async(url)).await {
        Err(_) => Err(no_service(url, format!("it did not answer within {} s", wait.as_secs_f32()))),
        Ok(Err(e)) => Err(no_service(url, e)),
        Ok(Ok((ws, _))) => Ok(ws),
    }
}

/// The first message: asks for the full state and names this program's session profile.
async fn hello(ws: &mut Socket) -> Result<()> {
    let mut msg = ServiceMsg::default();
    let profile = SessionConfigure {
        profile: Some(ProfileConfig { name: "phantom-heist".into(), required_version: None }),
        basis: None,
        serialization: None,
        sdf: None,
    };
    haply::state::update_entire_msg(&[Command::ConfigureSession(profile)], &mut msg)
        .map_err(|e| HapticoError::InvalidConfig(format!("building the Haply session message: {e}")))?;
    send_json(ws, &msg).await
}

async fn send_json(ws: &mut Socket, msg: &ServiceMsg) -> Result<()> {
    let text = serde_json::to_string(msg).map_err(|e| HapticoError::Usb(format!("encoding a Haply command: {e}")))?;
    match tokio::time::timeout(SEND_TIMEOUT, ws.send(Message::Text(text.into()))).await {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(HapticoError::Usb(format!("the Haply service connection failed: {e}"))),
        Err(_) => Err(HapticoError::Usb("the Haply service stopped reading commands".into())),
    }
}

/// Merges one text frame into `state` with the crate's own merge.
async fn merge(state: &SharedState, text: String, first: &mut bool) {
    haply::state::update_state_on_message(state.clone(), text, first, VerseGripDuplicateMode::default()).await;
}

/// The next text frame before `deadline` (`None` once it passed, other frames skipped), or what went
/// wrong with the connection (`during`: while doing what).
async fn next_text(ws: &mut Socket, deadline: tokio::time::Instant, during: &str) -> Result<Option<String>> {
    loop {
        match tokio::time::timeout_at(deadline, ws.next()).await {
            Err(_) => return Ok(None),
            Ok(Some(Ok(Message::Text(text)))) => return Ok(Some(text.to_string())),
            Ok(Some(Ok(_))) => {}
            Ok(Some(Err(e))) => return Err(HapticoError::Usb(format!("the Haply service connection failed: {e}"))),
            Ok(None) => return Err(HapticoError::Usb(format!("the Haply service closed the connection{during}"))),
        }
    }
}

/// Reads frames until the service lists an Inverse3; its id.
async fn first_frame(ws: &mut Socket, state: &SharedState, wait: Duration) -> Result<String> {
    let deadline = tokio::time::Instant::now() + wait;
    let mut first = true;
    let mut frames = 0u32;
    while let Some(text) = next_text(ws, deadline, "").await? {
        frames += 1;
        merge(state, text, &mut first).await;
        if let Some(d) = state.lock().await.data.inverse3.first() {
            return Ok(d.device_id.clone());
        }
    }
    Err(HapticoError::NoDevice {
        wanted: "Inverse3 on the Haply Inverse Service".into(),
        hint: format!(
            "the service answered ({frames} state messages in {} s) but lists no Inverse3: plug it in, switch it \
             on and check the service's dashboard",
            wait.as_secs_f32()
        ),
    })
}

/// Reads the grip for [`CENTRING`] (answering each frame with no force) and returns the mean position
/// (our axes), or what was wrong when it moved or no position came.
async fn centre_on_the_grip(ws: &mut Socket, state: &SharedState, device_id: &str) -> Result<Vec3> {
    let zero = force_msg(device_id, Vec3::ZERO);
    let deadline = tokio::time::Instant::now() + CENTRING;
    let mut first = false;
    let (mut lo, mut hi, mut sum, mut n) = (Vec3::INFINITY, Vec3::NEG_INFINITY, Vec3::ZERO, 0u32);
    send_json(ws, &zero).await?;
    while let Some(text) = next_text(ws, deadline, " while centring").await? {
        merge(state, text, &mut first).await;
        let p = state.lock().await.data.inverse3.iter().find(|d| d.device_id == device_id).and_then(position);
        if let Some(p) = p {
            (lo, hi, sum, n) = (lo.min(p), hi.max(p), sum + p, n + 1);
        }
        send_json(ws, &zero).await?;
    }
    if n == 0 {
        return Err(HapticoError::Usb(format!(
            "the Haply service sent no position of the Inverse3 {device_id} in {} s",
            CENTRING.as_secs_f32()
        )));
    }
    let moved = (hi - lo).length();
    if moved > HOLD_STILL_M {
        return Err(HapticoError::InvalidConfig(format!(
            "the grip moved {:.0} mm while the Inverse3 was being centred: hold it still where you want to play, \
             then start again",
            moved * 1000.0
        )));
    }
    Ok(sum / n as f32)
}

fn position(d: &Inverse3Device) -> Option<Vec3> {
    d.state.cursor_position.map(to_ours).filter(|p| p.is_finite())
}

fn force_msg(device_id: &str, force: Vec3) -> ServiceMsg {
    let mut msg = ServiceMsg::default();
    msg.session.force_render_full_state = None;
    let command = Command::SetCursorForce { device_id: device_id.to_owned(), vector: to_haply(force), execute: true };
    // Merging a force command into an empty message cannot fail.
    let _ = haply::state::update_entire_msg(&[command], &mut msg);
    msg
}

/// The service's positions to the device frame: the centre found while centring goes to `centre_at`.
#[derive(Clone, Copy, Debug)]
struct Map {
    centre: Vec3,
    centre_at: Vec3,
}

impl Map {
    fn state(&self, d: &Inverse3Device, t_us: u64) -> DeviceState {
        let p = position(d).unwrap_or(self.centre);
        let v = d.state.cursor_velocity.map(to_ours).filter(|v| v.is_finite()).unwrap_or(Vec3::ZERO);
        DeviceState {
            pose: Pose::from_translation(self.centre_at + (p - self.centre)),
            linear_velocity: v,
            timestamp_us: t_us,
            ..DeviceState::default()
        }
    }
}

/// The I/O thread: each state frame is merged, handed over and answered with the newest force; with no
/// frame for [`KEEPALIVE`] the force is sent anyway. Ends when the haptic side lets go (leaving the
/// device without force) or the service goes away (flagged in `status`).
async fn exchange(
    mut ws: Socket,
    mut io: IoThread,
    state: SharedState,
    device_id: String,
    map: Map,
    status: Arc<HaplyStatus>,
) {
    let mut keepalive = tokio::time::interval(KEEPALIVE);
    keepalive.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut first = false;
    let mut last_sent = Vec3::NAN;
    let mut last_send = Instant::now();
    let mut awaited: Option<(Vec3, Instant)> = None;
    let started = Instant::now();
    loop {
        let frame = tokio::select! {
            msg = ws.next() => Some(msg),
            _ = keepalive.tick() => None,
        };
        match frame {
            Some(Some(Ok(Message::Text(text)))) => {
                merge(&state, text.to_string(), &mut first).await;
                let data = state.lock().await;
                if let Some(d) = data.data.inverse3.iter().find(|d| d.device_id == device_id) {
                    io.states.write(map.state(d, io.clock.now_us()));
                    status.saw(d);
                    let reported = d.state.current_cursor_force.map(to_ours);
                    if let (Some((f, sent)), Some(r)) = (awaited, reported)
                        && (f - r).length() < 1e-4
                    {
                        status.round_trip(sent.elapsed().as_micros() as u64);
                        awaited = None;
                    }
                }
            }
            Some(Some(Ok(Message::Close(_))) | Some(Err(_)) | None) => {
                status.disconnected.store(true, Ordering::Release);
                log::warn!("the Haply service closed the connection after {:.1} s", started.elapsed().as_secs_f32());
                return;
            }
            Some(Some(Ok(_))) => continue,
            None if io.stopping() => {
                let _ = send_json(&mut ws, &force_msg(&device_id, Vec3::ZERO)).await;
                // Close and wait for the service's answer: a socket dropped at once may be reset before
                // the service read the last force.
                let _ = tokio::time::timeout(SEND_TIMEOUT, async {
                    let _ = ws.close(None).await;
                    while let Some(Ok(_)) = ws.next().await {}
                })
                .await;
                return;
            }
            None if last_send.elapsed() < KEEPALIVE => continue,
            None => {}
        }
        if io.stopping() {
            continue; // the keepalive tick releases the device
        }
        let ForceTorque { force, .. } = io.newest_force();
        if send_json(&mut ws, &force_msg(&device_id, force)).await.is_err() {
            status.disconnected.store(true, Ordering::Release);
            log::warn!("the Haply service stopped taking commands after {:.1} s", started.elapsed().as_secs_f32());
            return;
        }
        last_send = Instant::now();
        status.commands.fetch_add(1, Ordering::Relaxed);
        io.count_exchange();
        if awaited.is_none() && (force - last_sent).length() > 1e-3 {
            awaited = Some((force, last_send));
        }
        last_sent = force;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frames_map_both_ways_and_up_is_up() {
        let v = Vec3D { x: 0.1, y: 0.2, z: 0.3 };
        assert_eq!(to_haply(to_ours(v)), v);
        // Haply's z is up; ours is y.
        assert_eq!(to_ours(Vec3D { x: 0.0, y: 0.0, z: 1.0 }), Vec3::Y);
        // Away from the player is our −z.
        assert_eq!(to_ours(Vec3D { x: 0.0, y: 1.0, z: 0.0 }), Vec3::NEG_Z);
    }

    #[test]
    fn a_force_command_is_the_crates_set_cursor_force_in_haplys_axes() {
        let msg = force_msg("049D", Vec3::new(0.0, 1.5, 0.0));
        let json: serde_json::Value = serde_json::to_value(&msg).expect("encodes");
        let cmd = &json["inverse3"][0];
        assert_eq!(cmd["device_id"], "049D");
        assert_eq!(cmd["commands"]["set_cursor_force"]["vector"]["z"], 1.5);
        assert!(json["session"].get("force_render_full_state").is_none(), "{json}");
    }

    #[test]
    fn the_centre_goes_where_asked() {
        let map = Map { centre: Vec3::new(0.0, 0.2, 0.1), centre_at: Vec3::new(0.0, 0.06, 0.07) };
        let mut d = Inverse3Device::default();
        d.state.cursor_position = Some(to_haply(Vec3::new(0.01, 0.2, 0.1)));
        let s = map.state(&d, 5);
        assert!((s.pose.translation - Vec3::new(0.01, 0.06, 0.07)).length() < 1e-6);
        assert_eq!(s.timestamp_us, 5);
    }
}
