//! The fleet services started beside the game loop on demand: the health and metrics endpoint and the
//! Agones link (the `fleet` feature).

use std::net::SocketAddr;

use super::{Fleet, agones, http};

/// Which fleet services to start beside the game loop.
#[derive(Clone, Debug, Default)]
pub struct FleetOptions {
    /// Serve `/healthz` and `/metrics` on this TCP address.
    pub metrics: Option<SocketAddr>,
    /// Report to the Agones sidecar.
    pub agones: Option<agones::AgonesOptions>,
}

/// The running fleet services of a server.
pub struct FleetServices {
    /// The health and metrics endpoint.
    pub http: Option<http::MetricsServer>,
    /// The Agones link.
    pub agones: Option<agones::AgonesLink>,
}

impl FleetServices {
    /// Starts what `options` asks for, on threads of their own, for the server whose fleet side is
    /// `fleet` and which Agones knows as `game` (its sockets are bound: Agones is told Ready).
    pub fn start(fleet: &Fleet, game: agones::GameServerInfo, options: &FleetOptions) -> anyhow::Result<Self> {
        use anyhow::Context as _;
        let http = match options.metrics {
            Some(bind) => Some(
                http::MetricsServer::spawn(bind, fleet.clone())
                    .with_context(|| format!("cannot serve metrics on TCP {bind}"))?,
            ),
            None => None,
        };
        let agones = match &options.agones {
            Some(o) => Some(agones::AgonesLink::spawn(o.clone(), fleet.clone(), game)?),
            None => None,
        };
        Ok(Self { http, agones })
    }

    /// After the game loop ended: tells Agones `Shutdown` (if linked) and stops the endpoint.
    pub fn shut_down(self) {
        if let Some(link) = self.agones {
            link.shut_down();
        }
        drop(self.http);
    }
}
