//! `--metrics ADDR`: `/healthz` and `/metrics` over HTTP/1.1 (hyper), on a thread of its own.
//!
//! Bounded like every endpoint of the server: at most [`MAX_CONNECTIONS`] at once (more are closed at
//! once), request heads within [`HEAD_TIMEOUT`], every connection closed after [`CONNECTION_LIFETIME`].

use bevy::log::{error, warn};
use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use http_body_util::Full;
use hyper::body::{Bytes, Incoming};
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};

use super::Fleet;

/// Connections served at once.
pub const MAX_CONNECTIONS: usize = 16;
/// Time a client has to send a request head.
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(2);
/// Time a connection may stay open (a scraper keeping it alive opens another).
pub const CONNECTION_LIFETIME: Duration = Duration::from_secs(30);

/// The answer to one request: status, content type, body.
pub fn answer(fleet: &Fleet, method: &Method, path: &str) -> (StatusCode, &'static str, String) {
    const TEXT: &str = "text/plain; charset=utf-8";
    match (method, path) {
        (&Method::GET, "/healthz") => {
            let (healthy, text) = fleet.health();
            (if healthy { StatusCode::OK } else { StatusCode::SERVICE_UNAVAILABLE }, TEXT, text + "\n")
        }
        (&Method::GET, "/metrics") => {
            (StatusCode::OK, "application/openmetrics-text; version=1.0.0; charset=utf-8", fleet.metrics.encode())
        }
        (_, "/healthz" | "/metrics") => (StatusCode::METHOD_NOT_ALLOWED, TEXT, "only GET\n".into()),
        _ => (StatusCode::NOT_FOUND, TEXT, "not found: try /healthz or /metrics\n".into()),
    }
}

/// A running health and metrics endpoint; stops when dropped.
pub struct MetricsServer {
    /// The address it listens on.
    pub addr: SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl MetricsServer {
    /// Binds `bind` (TCP) and serves `fleet`'s health and metrics.
    pub fn spawn(bind: SocketAddr, fleet: Fleet) -> std::io::Result<Self> {
        let listener = std::net::TcpListener::bind(bind)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let runtime = tokio::runtime::Builder::new_current_thread().enable_io().enable_time().build()?;
        let (stop, stopped) = tokio::sync::oneshot::channel();
        let thread = std::thread::Builder::new().name("metrics-http".into()).spawn(move || {
            runtime.block_on(async move {
                match tokio::net::TcpListener::from_std(listener) {
                    Ok(listener) => serve(listener, fleet, stopped).await,
                    Err(e) => error!("metrics endpoint: cannot serve on {addr}: {e}"),
                }
            });
        })?;
        Ok(Self { addr, stop: Some(stop), thread: Some(thread) })
    }
}

impl Drop for MetricsServer {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

async fn serve(listener: tokio::net::TcpListener, fleet: Fleet, mut stop: tokio::sync::oneshot::Receiver<()>) {
    let slots = Arc::new(tokio::sync::Semaphore::new(MAX_CONNECTIONS));
    loop {
        let accepted = tokio::select! {
            _ = &mut stop => break,
            accepted = listener.accept() => accepted,
        };
        let stream = match accepted {
            Ok((stream, _)) => stream,
            Err(e) => {
                warn!("metrics endpoint: accept failed: {e}");
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(slot) = slots.clone().try_acquire_owned() else {
            continue; // every slot is taken: this connection is closed unanswered
        };
        let fleet = fleet.clone();
        tokio::spawn(async move {
            let service = hyper::service::service_fn(move |request: Request<Incoming>| {
                let (status, content_type, body) = answer(&fleet, request.method(), request.uri().path());
                let response = Response::builder()
                    .status(status)
                    .header(hyper::header::CONTENT_TYPE, content_type)
                    .body(Full::new(Bytes::from(body)))
                    .unwrap_or_default();
                async move { Ok::<_, Infallible>(response) }
            });
            let connection = hyper::server::conn::http1::Builder::new()
                .timer(TokioTimer::new())
                .header_read_timeout(HEAD_TIMEOUT)
                .serve_connection(TokioIo::new(stream), service);
            let _ = tokio::time::timeout(CONNECTION_LIFETIME, connection).await;
            drop(slot);
        });
    }
}
