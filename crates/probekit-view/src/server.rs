//! The HTTP server: a `tiny_http` listener and a few worker threads that
//! take requests in turn (several browser tabs, and a tab's parallel
//! requests, are served at once; a truth request that waits holds one
//! thread). A request that panics a handler gets 500, and the thread goes on.

use crate::api::{handle, Reply, State, MAX_BODY};
use crate::setup::Viewer;
use crate::ViewError;
use std::io::Read;
use std::net::{IpAddr, SocketAddr, TcpListener};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// Threads answering requests.
pub const WORKERS: usize = 8;

/// How often an idle worker checks whether to stop.
const POLL: Duration = Duration::from_millis(100);

/// A running server ([`Viewer::start`]); [`Running::stop`] ends it.
pub struct Running {
    addr: SocketAddr,
    state: Arc<State>,
    stop: Arc<AtomicBool>,
    workers: Vec<JoinHandle<()>>,
}

impl Viewer {
    /// Binds `addr`:`port` (0: a free port) and starts serving. A port in
    /// use is [`ViewError::PortInUse`], naming it.
    pub fn start(self, addr: IpAddr, port: u16) -> Result<Running, ViewError> {
        let listener = TcpListener::bind((addr, port)).map_err(|e| {
            if e.kind() == std::io::ErrorKind::AddrInUse {
                ViewError::PortInUse { addr, port }
            } else {
                ViewError::Bind {
                    addr,
                    port,
                    message: e.to_string(),
                }
            }
        })?;
        let local = listener.local_addr().map_err(|e| ViewError::Bind {
            addr,
            port,
            message: e.to_string(),
        })?;
        let server =
            tiny_http::Server::from_listener(listener, None).map_err(|e| ViewError::Bind {
                addr,
                port,
                message: e.to_string(),
            })?;
        let server = Arc::new(server);
        let state = Arc::new(State::new(self.data));
        let stop = Arc::new(AtomicBool::new(false));
        let workers = (0..WORKERS)
            .filter_map(|i| {
                let (server, state, stop) = (server.clone(), state.clone(), stop.clone());
                std::thread::Builder::new()
                    .name(format!("http-{i}"))
                    .spawn(move || worker(&server, &state, &stop))
                    .ok()
            })
            .collect();
        Ok(Running {
            addr: local,
            state,
            stop,
            workers,
        })
    }
}

impl Running {
    /// The address and port served.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL (`http://ADDR:PORT/`; an unspecified bind address
    /// shows as 127.0.0.1, where this machine reaches it).
    pub fn url(&self) -> String {
        let ip = match self.addr.ip() {
            IpAddr::V4(v) if v.is_unspecified() => IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
            IpAddr::V6(v) if v.is_unspecified() => IpAddr::V6(std::net::Ipv6Addr::LOCALHOST),
            ip => ip,
        };
        format!("http://{}/", SocketAddr::new(ip, self.addr.port()))
    }

    /// Stops serving: the workers finish the requests they hold and exit,
    /// the truth worker stops at its next normal, the port is released.
    pub fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        for w in self.workers {
            let _ = w.join();
        }
        self.state.truth.stop();
        // The last worker dropped the server; its accept thread lets go of
        // the listener a moment later. Wait for that (briefly), so that the
        // port is free when this returns.
        let deadline = std::time::Instant::now() + Duration::from_secs(2);
        while TcpListener::bind(self.addr).is_err() && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

fn worker(server: &tiny_http::Server, state: &State, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        match server.recv_timeout(POLL) {
            Ok(Some(rq)) => respond(state, rq),
            Ok(None) => {}
            // The listener failed: nothing more will come.
            Err(_) => std::thread::sleep(POLL),
        }
    }
}

fn respond(state: &State, mut rq: tiny_http::Request) {
    let method = rq.method().as_str().to_string();
    let url = rq.url().to_string();
    let mut body = Vec::new();
    let too_long = rq.body_length().is_some_and(|n| n > MAX_BODY) || {
        let read = rq
            .as_reader()
            .take(MAX_BODY as u64 + 1)
            .read_to_end(&mut body);
        read.is_err() || body.len() > MAX_BODY
    };
    let reply = if too_long {
        Reply::error(413, format!("request body over {MAX_BODY} bytes"))
    } else {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            handle(state, &method, &url, &body)
        }))
        .unwrap_or_else(|_| Reply::error(500, "internal error"))
    };
    let head = method == "HEAD";
    let mut response = tiny_http::Response::from_data(if head { Vec::new() } else { reply.body })
        .with_status_code(reply.status);
    let headers = [
        ("Content-Type", reply.content_type),
        ("Cache-Control", "no-store"),
        ("X-Content-Type-Options", "nosniff"),
    ];
    for (k, v) in headers.into_iter().chain(reply.allow.map(|a| ("Allow", a))) {
        if let Ok(h) = tiny_http::Header::from_bytes(k.as_bytes(), v.as_bytes()) {
            response = response.with_header(h);
        }
    }
    // A client that went away is not an error of the server.
    let _ = rq.respond(response);
}
