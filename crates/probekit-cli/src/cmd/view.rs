//! `probekit view`: look at a bake in the browser — a local server with a
//! WebGL2 page and a JSON API (crate `probekit-view`, docs/view.md).

use anyhow::Result;
use clap::Args;
use std::net::IpAddr;
use std::path::PathBuf;

/// Arguments of `probekit view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A cloud or volume `.probes` file.
    pub probes: PathBuf,
    /// The scene (default: the one the file was baked from; without one the
    /// page shows the probes alone).
    #[arg(long)]
    pub scene: Option<String>,
    /// Serve a scene whose lighting differs from the bake's (the page warns).
    #[arg(long)]
    pub allow_other_scene: bool,
    /// Port to serve on (0 picks a free one).
    #[arg(long, default_value_t = 8734)]
    pub port: u16,
    /// Address to listen on (default: this machine only).
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: IpAddr,
    /// Open the page in the system's browser.
    #[arg(long)]
    pub open: bool,
    /// Path-traced samples per normal of a truth request.
    #[arg(long, default_value_t = probekit_view::DEFAULT_TRUTH_SAMPLES)]
    pub truth_samples: u32,
}

/// Runs `probekit view`: checks the file and scene, prints the URL, serves
/// until Ctrl-C.
pub fn run(a: &ViewArgs) -> Result<()> {
    let mut config = probekit_view::ViewConfig::new(&a.probes);
    config.scene = a.scene.clone();
    config.allow_other_scene = a.allow_other_scene;
    config.bind = a.bind;
    config.port = a.port;
    config.truth_samples = a.truth_samples;
    probekit_view::serve(&config, &mut |w| eprintln!("warning: {w}"), &mut |url| {
        println!("probekit view: {url} (Ctrl-C stops)");
        if a.open && !probekit_view::open_browser(url) {
            eprintln!("warning: no browser could be started; open {url}");
        }
    })?;
    Ok(())
}
