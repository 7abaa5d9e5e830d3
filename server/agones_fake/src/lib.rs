//! A stand-in for the Agones SDK server (the sidecar beside every game server pod), speaking the same
//! gRPC protocol: its server side is generated from the `.proto` files that ship in the `agones` crate
//! (build.rs), so the official client talks to it unchanged. Agones' own local SDK server is a Go
//! binary that cannot be installed here.
//!
//! It keeps what a real sidecar keeps (the game server's state, labels, annotations, Counters and
//! Lists, with Agones' rules: only declared ones exist, counts stay within capacity, list values are
//! unique) and records every call, so tests can check what the game server said and when.
#![warn(missing_docs)]
// tonic's service traits return `tonic::Status` as the error: the fake must too.
#![allow(clippy::result_large_err)]

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tonic::{Request, Response, Status, Streaming};

#[allow(missing_docs, dead_code, clippy::all, clippy::pedantic)]
mod api {
    tonic::include_proto!("agones.dev.sdk");
    pub mod beta {
        tonic::include_proto!("agones.dev.sdk.beta");
    }
}

use api::beta;

/// What the sidecar knows and what it was told.
#[derive(Clone, Debug, Default)]
pub struct Recorded {
    /// The game server's state as Agones would report it: `Scheduled`, `Ready`, `Allocated`,
    /// `Reserved`, `Shutdown`.
    pub state: String,
    /// `Ready` calls.
    pub ready: u32,
    /// `Shutdown` calls.
    pub shutdown: u32,
    /// When each health ping arrived.
    pub health_pings: Vec<Instant>,
    /// Labels set (keys as the game server gave them; Agones prefixes them `agones.dev/sdk-`).
    pub labels: BTreeMap<String, String>,
    /// Annotations set.
    pub annotations: BTreeMap<String, String>,
    /// Counters: (count, capacity).
    pub counters: BTreeMap<String, (i64, i64)>,
    /// Lists: (capacity, values in the order added).
    pub lists: BTreeMap<String, (i64, Vec<String>)>,
    /// Every call, in order, as one line each (`Ready`, `UpdateCounter sessions count=1`, …).
    pub calls: Vec<String>,
    /// The game server's ports (name, host port), as the spec and Agones' port allocator gave them.
    pub ports: Vec<(String, u16)>,
}

/// Which Counters and Lists the GameServer spec declares (only those exist, as in Agones).
#[derive(Clone, Debug, Default)]
pub struct Declared {
    /// Counter names and their initial capacities.
    pub counters: Vec<(String, i64)>,
    /// List names and their initial capacities.
    pub lists: Vec<(String, i64)>,
    /// Ports (name, host port) in the game server's status.
    pub ports: Vec<(String, u16)>,
}

struct Shared {
    recorded: Mutex<Recorded>,
    changes: tokio::sync::watch::Sender<api::GameServer>,
}

fn lock(shared: &Shared) -> MutexGuard<'_, Recorded> {
    shared.recorded.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Shared {
    /// Records `call`, applies `change`, and tells watchers the new game server.
    fn update<T>(&self, call: String, change: impl FnOnce(&mut Recorded) -> Result<T, Status>) -> Result<T, Status> {
        let mut r = lock(self);
        r.calls.push(call);
        let out = change(&mut r)?;
        let gs = game_server(&r);
        drop(r);
        self.changes.send_replace(gs);
        Ok(out)
    }
}

fn game_server(r: &Recorded) -> api::GameServer {
    use api::game_server::{ObjectMeta, Status as GsStatus, status};
    api::GameServer {
        object_meta: Some(ObjectMeta {
            name: "agones-fake".into(),
            namespace: "default".into(),
            labels: r.labels.iter().map(|(k, v)| (format!("agones.dev/sdk-{k}"), v.clone())).collect(),
            annotations: r.annotations.iter().map(|(k, v)| (format!("agones.dev/sdk-{k}"), v.clone())).collect(),
            ..Default::default()
        }),
        spec: None,
        status: Some(GsStatus {
            state: r.state.clone(),
            address: "127.0.0.1".into(),
            ports: r
                .ports
                .iter()
                .map(|(name, port)| status::Port { name: name.clone(), port: i32::from(*port) })
                .collect(),
            counters: r
                .counters
                .iter()
                .map(|(k, &(count, capacity))| (k.clone(), status::CounterStatus { count, capacity }))
                .collect(),
            lists: r
                .lists
                .iter()
                .map(|(k, (capacity, values))| {
                    (k.clone(), status::ListStatus { capacity: *capacity, values: values.clone() })
                })
                .collect(),
            ..Default::default()
        }),
    }
}

/// Agones caps Counter and List capacities at this.
const MAX_LIST_CAPACITY: i64 = 1000;

#[derive(Clone)]
struct Sdk(Arc<Shared>);

#[tonic::async_trait]
impl api::sdk_server::Sdk for Sdk {
    async fn ready(&self, _: Request<api::Empty>) -> Result<Response<api::Empty>, Status> {
        self.0.update("Ready".into(), |r| {
            r.ready += 1;
            if r.state != "Allocated" {
                r.state = "Ready".into();
            }
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }

    async fn allocate(&self, _: Request<api::Empty>) -> Result<Response<api::Empty>, Status> {
        self.0.update("Allocate".into(), |r| {
            r.state = "Allocated".into();
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }

    async fn shutdown(&self, _: Request<api::Empty>) -> Result<Response<api::Empty>, Status> {
        self.0.update("Shutdown".into(), |r| {
            r.shutdown += 1;
            r.state = "Shutdown".into();
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }

    async fn health(&self, request: Request<Streaming<api::Empty>>) -> Result<Response<api::Empty>, Status> {
        let mut pings = request.into_inner();
        while let Some(_ping) = pings.message().await? {
            lock(&self.0).health_pings.push(Instant::now());
        }
        Ok(Response::new(api::Empty {}))
    }

    async fn get_game_server(&self, _: Request<api::Empty>) -> Result<Response<api::GameServer>, Status> {
        Ok(Response::new(game_server(&lock(&self.0))))
    }

    type WatchGameServerStream =
        std::pin::Pin<Box<dyn tokio_stream::Stream<Item = Result<api::GameServer, Status>> + Send + 'static>>;

    async fn watch_game_server(&self, _: Request<api::Empty>) -> Result<Response<Self::WatchGameServerStream>, Status> {
        use tokio_stream::StreamExt as _;
        lock(&self.0).calls.push("WatchGameServer".into());
        let changes = tokio_stream::wrappers::WatchStream::new(self.0.changes.subscribe());
        Ok(Response::new(Box::pin(changes.map(Ok))))
    }

    async fn set_label(&self, request: Request<api::KeyValue>) -> Result<Response<api::Empty>, Status> {
        let kv = request.into_inner();
        self.0.update(format!("SetLabel {}={}", kv.key, kv.value), |r| {
            r.labels.insert(kv.key, kv.value);
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }

    async fn set_annotation(&self, request: Request<api::KeyValue>) -> Result<Response<api::Empty>, Status> {
        let kv = request.into_inner();
        self.0.update(format!("SetAnnotation {}={}", kv.key, kv.value), |r| {
            r.annotations.insert(kv.key, kv.value);
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }

    async fn reserve(&self, request: Request<api::Duration>) -> Result<Response<api::Empty>, Status> {
        let seconds = request.into_inner().seconds;
        self.0.update(format!("Reserve {seconds} s"), |r| {
            r.state = "Reserved".into();
            Ok(())
        })?;
        Ok(Response::new(api::Empty {}))
    }
}

#[derive(Clone)]
struct Beta(Arc<Shared>);

fn counter_of<'a>(r: &'a mut Recorded, name: &str) -> Result<&'a mut (i64, i64), Status> {
    r.counters.get_mut(name).ok_or_else(|| Status::not_found(format!("counter not found: {name}")))
}

fn list_of<'a>(r: &'a mut Recorded, name: &str) -> Result<&'a mut (i64, Vec<String>), Status> {
    r.lists.get_mut(name).ok_or_else(|| Status::not_found(format!("list not found: {name}")))
}

fn counter(name: &str, &(count, capacity): &(i64, i64)) -> beta::Counter {
    beta::Counter { name: name.into(), count, capacity }
}

fn list(name: &str, (capacity, values): &(i64, Vec<String>)) -> beta::List {
    beta::List { name: name.into(), capacity: *capacity, values: values.clone() }
}

#[tonic::async_trait]
impl beta::sdk_server::Sdk for Beta {
    async fn get_counter(&self, request: Request<beta::GetCounterRequest>) -> Result<Response<beta::Counter>, Status> {
        let name = request.into_inner().name;
        let mut r = lock(&self.0);
        let c = counter_of(&mut r, &name)?;
        Ok(Response::new(counter(&name, c)))
    }

    async fn update_counter(
        &self,
        request: Request<beta::UpdateCounterRequest>,
    ) -> Result<Response<beta::Counter>, Status> {
        let update = request
            .into_inner()
            .counter_update_request
            .ok_or_else(|| Status::invalid_argument("no CounterUpdateRequest"))?;
        let mut call = format!("UpdateCounter {}", update.name);
        if let Some(c) = update.count {
            call += &format!(" count={c}");
        }
        if let Some(c) = update.capacity {
            call += &format!(" capacity={c}");
        }
        if update.count_diff != 0 {
            call += &format!(" diff={}", update.count_diff);
        }
        let name = update.name.clone();
        let c = self.0.update(call, |r| {
            let c = counter_of(r, &update.name)?;
            let capacity = update.capacity.unwrap_or(c.1);
            if !(0..=MAX_LIST_CAPACITY).contains(&capacity) {
                return Err(Status::out_of_range(format!("capacity {capacity} is outside 0..={MAX_LIST_CAPACITY}")));
            }
            let count = update.count.unwrap_or(c.0) + update.count_diff;
            if !(0..=capacity).contains(&count) {
                return Err(Status::out_of_range(format!("count {count} is outside 0..={capacity}")));
            }
            *c = (count, capacity);
            Ok(*c)
        })?;
        Ok(Response::new(counter(&name, &c)))
    }

    async fn get_list(&self, request: Request<beta::GetListRequest>) -> Result<Response<beta::List>, Status> {
        let name = request.into_inner().name;
        let mut r = lock(&self.0);
        let l = list_of(&mut r, &name)?;
        Ok(Response::new(list(&name, l)))
    }

    async fn update_list(&self, request: Request<beta::UpdateListRequest>) -> Result<Response<beta::List>, Status> {
        let update = request.into_inner();
        let new = update.list.ok_or_else(|| Status::invalid_argument("no List"))?;
        let paths = update.update_mask.map(|m| m.paths).unwrap_or_default();
        let name = new.name.clone();
        let l = self.0.update(format!("UpdateList {} {paths:?} capacity={}", new.name, new.capacity), |r| {
            let l = list_of(r, &new.name)?;
            for path in &paths {
                match path.as_str() {
                    "capacity" if (0..=MAX_LIST_CAPACITY).contains(&new.capacity) => {
                        l.0 = new.capacity;
                        l.1.truncate(new.capacity as usize);
                    }
                    "capacity" => return Err(Status::out_of_range(format!("capacity {}", new.capacity))),
                    "values" => l.1 = new.values.clone(),
                    other => return Err(Status::invalid_argument(format!("unknown field in the mask: {other}"))),
                }
            }
            Ok(l.clone())
        })?;
        Ok(Response::new(list(&name, &l)))
    }

    async fn add_list_value(
        &self,
        request: Request<beta::AddListValueRequest>,
    ) -> Result<Response<beta::List>, Status> {
        let add = request.into_inner();
        let name = add.name.clone();
        let l = self.0.update(format!("AddListValue {} {}", add.name, add.value), |r| {
            let l = list_of(r, &add.name)?;
            if l.1.contains(&add.value) {
                return Err(Status::already_exists(format!("{} is already in {}", add.value, add.name)));
            }
            if l.1.len() as i64 >= l.0 {
                return Err(Status::out_of_range(format!("{} is at its capacity {}", add.name, l.0)));
            }
            l.1.push(add.value.clone());
            Ok(l.clone())
        })?;
        Ok(Response::new(list(&name, &l)))
    }

    async fn remove_list_value(
        &self,
        request: Request<beta::RemoveListValueRequest>,
    ) -> Result<Response<beta::List>, Status> {
        let remove = request.into_inner();
        let name = remove.name.clone();
        let l = self.0.update(format!("RemoveListValue {} {}", remove.name, remove.value), |r| {
            let l = list_of(r, &remove.name)?;
            let at =
                l.1.iter()
                    .position(|v| *v == remove.value)
                    .ok_or_else(|| Status::not_found(format!("{} is not in {}", remove.value, remove.name)))?;
            l.1.remove(at);
            Ok(l.clone())
        })?;
        Ok(Response::new(list(&name, &l)))
    }
}

/// A running fake sidecar on loopback; stops when dropped.
pub struct FakeAgones {
    /// Its gRPC address (`127.0.0.1:PORT`): give the port to the game server as `AGONES_SDK_GRPC_PORT`.
    pub addr: SocketAddr,
    shared: Arc<Shared>,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl FakeAgones {
    /// Serves on `bind` (port 0 picks a free one) with the Counters and Lists of `declared`, the game
    /// server `Scheduled`.
    pub fn start(bind: SocketAddr, declared: Declared) -> anyhow::Result<Self> {
        let recorded = Recorded {
            state: "Scheduled".into(),
            counters: declared.counters.into_iter().map(|(n, cap)| (n, (0, cap))).collect(),
            lists: declared.lists.into_iter().map(|(n, cap)| (n, (cap, Vec::new()))).collect(),
            ports: declared.ports,
            ..Default::default()
        };
        let (changes, _) = tokio::sync::watch::channel(game_server(&recorded));
        let shared = Arc::new(Shared { recorded: Mutex::new(recorded), changes });
        let listener = std::net::TcpListener::bind(bind)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let (sdk, beta) = (Sdk(shared.clone()), Beta(shared.clone()));
        let thread = std::thread::Builder::new().name("agones-fake".into()).spawn(move || {
            runtime.block_on(async move {
                let listener = match tokio::net::TcpListener::from_std(listener) {
                    Ok(l) => l,
                    Err(e) => return log::error!("agones-fake: cannot serve on {addr}: {e}"),
                };
                let incoming = tokio_stream::wrappers::TcpListenerStream::new(listener);
                let serve = tonic::transport::Server::builder()
                    .add_service(api::sdk_server::SdkServer::new(sdk))
                    .add_service(beta::sdk_server::SdkServer::new(beta))
                    .serve_with_incoming(incoming);
                // Stopping drops the server and, with the runtime, every open connection: a graceful
                // shutdown would wait for clients that never hang up (a game server's health stream).
                tokio::select! {
                    served = serve => {
                        if let Err(e) = served {
                            log::error!("agones-fake: {e}");
                        }
                    }
                    _ = stopped => {}
                }
            });
        })?;
        Ok(Self { addr, shared, stop: Some(stop), thread: Some(thread) })
    }

    /// A copy of what it knows and was told so far.
    pub fn recorded(&self) -> Recorded {
        lock(&self.shared).clone()
    }

    /// Allocates the game server, as Agones' allocator does when a match is made: its state becomes
    /// `Allocated` and watchers are told.
    pub fn allocate(&self) {
        let _ = self.shared.update("(allocator) allocate".into(), |r| {
            r.state = "Allocated".into();
            Ok(())
        });
    }

    /// Waits until `ready(recorded)` holds, at most `limit`; true if it did.
    pub fn wait_for(&self, limit: Duration, ready: impl Fn(&Recorded) -> bool) -> bool {
        let deadline = Instant::now() + limit;
        loop {
            if ready(&lock(&self.shared)) {
                return true;
            }
            if Instant::now() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for FakeAgones {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
