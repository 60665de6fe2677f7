//! The page's files, compiled into the binary: nothing on disk is ever served, so no path
//! can reach outside them.

use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};

/// (path under /assets/, content type, bytes).
const ASSETS: &[(&str, &str, &[u8])] = &[
    (
        "rules.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/rules.js"),
    ),
    (
        "app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/serve/app.js"),
    ),
    (
        "style.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/serve/style.css"),
    ),
    (
        "vendor/leaflet/leaflet.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/serve/vendor/leaflet/leaflet.js"),
    ),
    (
        "vendor/leaflet/leaflet.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/serve/vendor/leaflet/leaflet.css"),
    ),
    (
        "vendor/leaflet/LICENSE",
        "text/plain; charset=utf-8",
        include_bytes!("../../assets/serve/vendor/leaflet/LICENSE"),
    ),
];

const PAGE: &str = include_str!("../../assets/serve/index.html");

pub fn page() -> Response {
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], PAGE).into_response()
}

/// The asset at `path`, or 404: only names in the table, compared whole.
pub fn get(path: &str) -> Response {
    match ASSETS.iter().find(|(name, _, _)| *name == path) {
        Some((_, kind, bytes)) => (
            [
                (header::CONTENT_TYPE, *kind),
                (header::CACHE_CONTROL, "public, max-age=600"),
            ],
            *bytes,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "not found\n").into_response(),
    }
}

/// The static explorer's file `name` (only names of the site, compared whole), or 404.
pub fn site_file(site: &[(String, axum::body::Bytes)], name: &str) -> Response {
    let kind = match name.rsplit_once('.').map(|(_, ext)| ext) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("json") => "application/json",
        _ => "text/plain; charset=utf-8",
    };
    match site.iter().find(|(n, _)| n == name) {
        Some((_, bytes)) => ([(header::CONTENT_TYPE, kind)], bytes.clone()).into_response(),
        None => (StatusCode::NOT_FOUND, "not found\n").into_response(),
    }
}
