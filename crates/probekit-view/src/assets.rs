//! The page's files, embedded in the binary: the viewer works offline, with
//! no build step for the page and nothing fetched from elsewhere.

/// One embedded file: its URL path, content type and bytes.
pub struct Asset {
    /// URL path (`/` for the page).
    pub path: &'static str,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// Contents.
    pub bytes: &'static [u8],
}

const HTML: &str = "text/html; charset=utf-8";
const JS: &str = "text/javascript; charset=utf-8";
const CSS: &str = "text/css; charset=utf-8";

/// Every file the page loads.
pub const ASSETS: [Asset; 8] = [
    Asset {
        path: "/",
        content_type: HTML,
        bytes: include_bytes!("../assets/index.html"),
    },
    Asset {
        path: "/style.css",
        content_type: CSS,
        bytes: include_bytes!("../assets/style.css"),
    },
    Asset {
        path: "/main.js",
        content_type: JS,
        bytes: include_bytes!("../assets/main.js"),
    },
    Asset {
        path: "/gl.js",
        content_type: JS,
        bytes: include_bytes!("../assets/gl.js"),
    },
    Asset {
        path: "/math.js",
        content_type: JS,
        bytes: include_bytes!("../assets/math.js"),
    },
    Asset {
        path: "/scene.js",
        content_type: JS,
        bytes: include_bytes!("../assets/scene.js"),
    },
    Asset {
        path: "/panel.js",
        content_type: JS,
        bytes: include_bytes!("../assets/panel.js"),
    },
    Asset {
        path: "/shaders.gen.js",
        content_type: JS,
        bytes: include_bytes!("../assets/shaders.gen.js"),
    },
];

/// The asset at `path` (`/index.html` is the page too).
pub fn find(path: &str) -> Option<&'static Asset> {
    let path = if path == "/index.html" { "/" } else { path };
    ASSETS.iter().find(|a| a.path == path)
}
