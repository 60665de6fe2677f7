//! How a request is answered: errors as the page sees them, the bounded queue for the one
//! engine with its time limit and cancellation, the cache of computed answers.

use super::{MAX_WAITING, REQUEST_LIMIT, S};
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use axum::body::Bytes;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// An error as the page sees it: invalid values 400 with the key and the reason, a full
/// queue or a request past its time 503, the rest 500.
pub(super) fn reply(e: Error) -> Response {
    match e {
        Error::InvalidSpec { field, reason } => {
            let reason = spelt(&reason);
            (
                StatusCode::BAD_REQUEST,
                format!("invalid value for {field}: {reason}\n"),
            )
                .into_response()
        }
        Error::Interrupted => {
            (StatusCode::SERVICE_UNAVAILABLE, "cancelled\n".to_string()).into_response()
        }
        e => (StatusCode::INTERNAL_SERVER_ERROR, format!("{e}\n")).into_response(),
    }
}

/// `text` with the settings it names (`crate::error::spell`) as the page's query keys:
/// `precision=f64`.
pub(super) fn spelt(text: &str) -> String {
    crate::error::spell(text, |field, value| match value {
        Some(v) => format!("{field}={v}"),
        None => field.to_string(),
    })
}

pub(super) fn busy(why: &str) -> Response {
    (
        StatusCode::SERVICE_UNAVAILABLE,
        [(header::RETRY_AFTER, "1")],
        format!("{why}\n"),
    )
        .into_response()
}

/// Sets the request's cancel flag when the request is dropped before its work finished
/// (the client went away, or the server stops), and counts it.
pub(super) struct CancelOnDrop {
    cancel: Arc<AtomicBool>,
    done: bool,
    shared: S,
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        self.shared.waiting.fetch_sub(1, Ordering::Relaxed);
        if !self.done {
            self.cancel.store(true, Ordering::Relaxed);
            self.shared
                .counters
                .cancelled
                .fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// Runs `work` on the engine, one request at a time, in the order they came: at most
/// [`MAX_WAITING`] wait, each for at most [`REQUEST_LIMIT`].
pub(super) async fn on_engine<T: Send + 'static>(
    shared: &S,
    work: impl FnOnce(&Engine, &Monitor) -> Result<T> + Send + 'static,
) -> std::result::Result<T, Response> {
    if shared.waiting.fetch_add(1, Ordering::Relaxed) >= MAX_WAITING {
        shared.waiting.fetch_sub(1, Ordering::Relaxed);
        shared.counters.refused.fetch_add(1, Ordering::Relaxed);
        return Err(busy("busy: too many requests waiting; try again"));
    }
    let cancel = Arc::new(AtomicBool::new(false));
    let mut guard = CancelOnDrop {
        cancel: cancel.clone(),
        done: false,
        shared: shared.clone(),
    };
    let engine = shared.engine.clone();
    let run = async move {
        let engine = engine.lock_owned().await;
        let monitor = Monitor::cancelled_by(cancel);
        tokio::task::spawn_blocking(move || work(&engine, &monitor)).await
    };
    let result = tokio::time::timeout(REQUEST_LIMIT, run).await;
    guard.done = true;
    match result {
        Err(_) => {
            guard.done = false;
            Err(busy("the request took too long and was cancelled"))
        }
        Ok(Err(e)) => Err(reply(Error::Gpu(format!("the work failed: {e}")))),
        Ok(Ok(r)) => r.map_err(reply),
    }
}

pub(super) fn cached(shared: &S, key: &str) -> Option<Bytes> {
    let hit = shared.cache.lock().ok()?.get(key).cloned();
    if hit.is_some() {
        shared.counters.cached.fetch_add(1, Ordering::Relaxed);
    }
    hit
}

pub(super) fn remember(shared: &S, key: String, bytes: Bytes) {
    if let Ok(mut c) = shared.cache.lock() {
        c.put(key, bytes);
    }
}

/// A tile's answer (bytes shared with the cache, not copied).
pub(super) fn png(bytes: Bytes, precision: &str) -> Response {
    (
        [
            (header::CONTENT_TYPE, "image/png".to_string()),
            (header::CACHE_CONTROL, "public, max-age=3600".to_string()),
            (
                header::HeaderName::from_static("x-chaoscope-precision"),
                precision.to_string(),
            ),
        ],
        bytes,
    )
        .into_response()
}

pub(super) fn json(value: serde_json::Value) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        value.to_string(),
    )
        .into_response()
}
