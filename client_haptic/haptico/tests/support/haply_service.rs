//! A local stand-in for the Haply Inverse Service: a WebSocket server on loopback that speaks the
//! service's messages (built from the `haply` crate's own types), streams an Inverse3's state at about
//! 1 kHz and notes the forces it is sent. Shared by haptico's protocol tests and the Phantom client's
//! end-to-end device test (included by path: no crate of its own).

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use ::haply::device_model::{
    DeviceConfig, Inverse3Device, Inverse3Message, Inverse3OutMsg, Inverse3State, Inverse3Status, ServiceData, Vec3D,
};
use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite::Message;

/// Where the fake grip rests, in Haply's frame (m): above the base, in front of it.
const REST: Vec3D = Vec3D { x: 0.0, y: -0.15, z: 0.2 };
/// Frames the grip rests for before it moves (longer than the centring).
const STILL_FRAMES: u32 = 600;

#[derive(Clone, Copy)]
pub struct Script {
    /// List an Inverse3 at all.
    pub inverse3: bool,
    /// Close the connection after this many frames.
    pub close_after: Option<u32>,
    /// Move the grip 1 mm per frame from the start (a player who does not hold still).
    pub wander: bool,
}

#[derive(Default)]
pub struct Seen {
    /// Force commands read.
    pub commands: u64,
    /// The force last commanded.
    pub last_force: Option<Vec3D>,
    /// The profile name the client's session asked for.
    pub profile: Option<String>,
}

pub struct FakeService {
    addr: SocketAddr,
    /// What clients commanded.
    pub seen: Arc<Mutex<Seen>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl FakeService {
    /// Serves `script` on a free loopback port until dropped (then every connection closes at once).
    pub fn start(script: Script) -> Self {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("binds loopback");
        listener.set_nonblocking(true).expect("non-blocking");
        let addr = listener.local_addr().expect("address");
        let seen = Arc::new(Mutex::new(Seen::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (seen2, stop2) = (seen.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().expect("runtime");
            rt.block_on(serve(listener, script, seen2, stop2));
        });
        Self { addr, seen, stop, thread: Some(thread) }
    }

    /// The service's address, as `--device haply:URL` takes it.
    pub fn url(&self) -> String {
        format!("ws://{}/", self.addr)
    }
}

impl Drop for FakeService {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn grip(frame: u32, script: Script) -> Vec3D {
    let moved = if script.wander { frame } else { frame.saturating_sub(STILL_FRAMES) };
    Vec3D { x: REST.x + moved as f32 * 1e-3 * if script.wander { 1.0 } else { 0.02 }, ..REST }
}

async fn serve(listener: std::net::TcpListener, script: Script, seen: Arc<Mutex<Seen>>, stop: Arc<AtomicBool>) {
    let listener = tokio::net::TcpListener::from_std(listener).expect("tokio listener");
    while !stop.load(Ordering::Acquire) {
        let Ok(Ok((tcp, _))) = tokio::time::timeout(Duration::from_millis(50), listener.accept()).await else {
            continue;
        };
        let Ok(ws) = tokio_tungstenite::accept_async(tcp).await else { continue };
        let (mut tx, mut rx) = ws.split();
        let mut tick = tokio::time::interval(Duration::from_millis(1));
        let mut frame = 0u32;
        while !stop.load(Ordering::Acquire) {
            tokio::select! {
                msg = rx.next() => match msg {
                    Some(Ok(Message::Text(text))) => note(&text, &seen),
                    Some(Ok(_)) => {}
                    _ => break,
                },
                _ = tick.tick() => {
                    if script.close_after.is_some_and(|n| frame >= n) {
                        let _ = tx.close().await;
                        break;
                    }
                    let text = state_frame(frame, script, seen.lock().expect("seen").last_force);
                    if tx.send(Message::Text(text.into())).await.is_err() {
                        // The client went: what it sent last is still to be read.
                        while let Ok(Some(Ok(Message::Text(text)))) =
                            tokio::time::timeout(Duration::from_millis(100), rx.next()).await
                        {
                            note(&text, &seen);
                        }
                        break;
                    }
                    frame += 1;
                }
            }
        }
    }
}

/// Notes what a client's message commands.
fn note(text: &str, seen: &Mutex<Seen>) {
    // The crate's ServiceMsg leaves empty lanes out, which its own Deserialize does not accept: read the
    // lanes, then each command as the crate's type.
    let msg: serde_json::Value = serde_json::from_str(text).expect("the client sends JSON");
    let mut s = seen.lock().expect("seen");
    if let Some(name) = msg["session"]["configure"]["profile"]["name"].as_str() {
        s.profile = Some(name.to_owned());
    }
    for out in msg["inverse3"].as_array().into_iter().flatten() {
        let out: Inverse3OutMsg = serde_json::from_value(out.clone()).expect("an Inverse3OutMsg");
        if let Some(f) = out.commands.and_then(|c| c.set_cursor_force) {
            s.commands += 1;
            s.last_force = Some(f.vector);
        }
    }
}

/// The first frame is the full payload (with the device's config), the next ones states only, as the
/// service sends them; each reports the force last commanded as the device's current force.
fn state_frame(frame: u32, script: Script, force: Option<Vec3D>) -> String {
    let state = Inverse3State {
        cursor_position: Some(grip(frame, script)),
        cursor_velocity: Some(Vec3D { x: 0.02, y: 0.0, z: 0.0 }),
        current_cursor_force: force,
        ..Inverse3State::default()
    };
    let status = Inverse3Status { calibrated: true, ready: true, started: true, ..Inverse3Status::default() };
    if !script.inverse3 {
        return serde_json::to_string(&ServiceData::default()).expect("encodes");
    }
    if frame == 0 {
        let device = Inverse3Device { device_id: "049D".into(), config: Some(DeviceConfig::default()), state, status };
        let data = ServiceData { inverse3: vec![device], ..ServiceData::default() };
        serde_json::to_string(&data).expect("encodes")
    } else {
        let msg = Inverse3Message { device_id: "049D".into(), state, status };
        serde_json::json!({ "inverse3": [msg] }).to_string()
    }
}
