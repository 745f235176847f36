//! # probekit-view — look at a bake in the browser
//!
//! `probekit view FILE.probes` checks a probe file and the scene it was baked
//! from, then serves, on a local HTTP port, one page (plain JavaScript and
//! WebGL2, every asset embedded in this crate: it works offline) and a JSON
//! API under `/api/` (`docs/view.md`). The page shows the scene's geometry,
//! the probes as spheres lit per pixel by their own SH, the tetrahedra, hull
//! faces and lights, and a test object lit by the SH that the runtime's query
//! returns for its position; a button path-traces the truth there and marks
//! where the probes leak.
//!
//! * [`open`] loads and checks everything (before any port is bound);
//! * [`Viewer::start`] binds and starts the server threads;
//! * [`serve`] does both and runs until Ctrl-C (what the CLI calls).
//!
//! The page's shaders are naga's GLSL ES 3.00 translation of
//! `shaders/probekit.wgsl` and the page's entry points
//! (`shaders/view.wgsl` in this crate), committed as
//! `assets/shaders.gen.js` and kept up to date by a test.

#![warn(missing_docs)]

mod api;
mod assets;
mod geometry;
pub mod query;
mod server;
mod setup;
mod truth;

pub use server::Running;
pub use setup::{open, Viewer};

use std::net::{IpAddr, Ipv4Addr};
use std::path::PathBuf;

/// Samples per normal of a truth computation unless the config says
/// otherwise: a few thousand, so that six normals take about a second on
/// the demo scene (relative standard error near 2 %).
pub const DEFAULT_TRUTH_SAMPLES: u32 = 4096;

/// What to view and where to serve it.
#[derive(Clone, Debug)]
pub struct ViewConfig {
    /// The `.probes` file (cloud or volume).
    pub probes: PathBuf,
    /// The scene (a path or `builtin:NAME`); `None`: the scene the file
    /// recorded.
    pub scene: Option<String>,
    /// Serve a scene whose lighting hash differs from the file's (the page
    /// then shows a warning banner) instead of refusing it.
    pub allow_other_scene: bool,
    /// Address to bind (default 127.0.0.1: this machine only).
    pub bind: IpAddr,
    /// Port; 0 picks a free one.
    pub port: u16,
    /// Samples per normal of a truth computation.
    pub truth_samples: u32,
}

impl ViewConfig {
    /// A config for `probes` with the defaults: the recorded scene, loopback,
    /// port 0 (a free one), [`DEFAULT_TRUTH_SAMPLES`].
    pub fn new(probes: impl Into<PathBuf>) -> Self {
        ViewConfig {
            probes: probes.into(),
            scene: None,
            allow_other_scene: false,
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 0,
            truth_samples: DEFAULT_TRUTH_SAMPLES,
        }
    }
}

/// Why the viewer cannot start. Every variant names the file, scene or
/// address concerned.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewError {
    /// The probe file cannot be read or is not a valid probe file.
    #[error("{file}: {message}")]
    Probes {
        /// The file, as named.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// The scene cannot be loaded.
    #[error("{scene}: {message}")]
    Scene {
        /// The scene, as named (with where the name came from).
        scene: String,
        /// What is wrong.
        message: String,
    },
    /// The scene's lighting differs from the one the file was baked from.
    #[error(
        "{file} was baked from {baked_scene} (lighting hash {baked_hash}), not from {scene} \
         (lighting hash {scene_hash}); give the scene it was baked from, or --allow-other-scene"
    )]
    SceneMismatch {
        /// The probe file.
        file: String,
        /// The scene it recorded.
        baked_scene: String,
        /// The lighting hash it recorded.
        baked_hash: String,
        /// The scene given.
        scene: String,
        /// Its lighting hash.
        scene_hash: String,
    },
    /// The port is taken by another program.
    #[error(
        "port {port} on {addr} is already in use; give another with --port (0 picks a free one)"
    )]
    PortInUse {
        /// The address.
        addr: IpAddr,
        /// The port.
        port: u16,
    },
    /// The address cannot be bound for another reason.
    #[error("cannot listen on {addr} port {port}: {message}")]
    Bind {
        /// The address.
        addr: IpAddr,
        /// The port.
        port: u16,
        /// The system's message.
        message: String,
    },
    /// A bad setting (e.g. zero truth samples).
    #[error("{0}")]
    Config(String),
    /// Ctrl-C could not be caught.
    #[error("cannot catch Ctrl-C: {0}")]
    Signal(String),
}

/// Opens `config.probes`, checks it and its scene, binds, calls `ready`
/// with the page's URL, and serves until Ctrl-C, then stops cleanly (the
/// threads finish their requests, a running truth computation stops at its
/// next normal). Warnings (a scene not found, another scene allowed) are
/// passed to `warn` before binding.
pub fn serve(
    config: &ViewConfig,
    warn: &mut dyn FnMut(&str),
    ready: &mut dyn FnMut(&str),
) -> Result<(), ViewError> {
    let viewer = open(config)?;
    for w in viewer.warnings() {
        warn(w);
    }
    let running = viewer.start(config.bind, config.port)?;
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    ctrlc::set_handler(move || {
        let _ = tx.send(());
    })
    .map_err(|e| ViewError::Signal(e.to_string()))?;
    ready(&running.url());
    let _ = rx.recv();
    running.stop();
    Ok(())
}

/// Opens `url` in the system's browser (`xdg-open` on Linux and BSD, `open`
/// on macOS, `start` on Windows), without waiting for it. Returns whether a
/// launcher could be started; never fails otherwise.
pub fn open_browser(url: &str) -> bool {
    let mut cmd = if cfg!(target_os = "macos") {
        std::process::Command::new("open")
    } else if cfg!(windows) {
        let mut c = std::process::Command::new("cmd");
        c.args(["/C", "start", ""]);
        c
    } else {
        std::process::Command::new("xdg-open")
    };
    cmd.arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .is_ok()
}
