//! `serve`: the explorer. A local HTTP server (axum on tokio) whose page (Leaflet, vendored)
//! shows flip, divergence and verdict maps as tiles computed on demand by the one engine,
//! and a clicked pixel's pendulum. Every tile is a pure function of its URL, so tiles are
//! cached by URL; requests wait for the engine in a bounded queue, and a request whose client
//! went away is cancelled at the engine's next dispatch.

mod assets;
pub mod view;

use std::collections::HashMap;
use std::net::IpAddr;
use std::num::NonZeroUsize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::body::Bytes;
use axum::extract::{Path, Query as AxumQuery, State as AxumState};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use lru::LruCache;

use self::view::{Kind, Query, View, World};
use crate::app::MapOutputs;
use crate::app::flip::FlipJob;
use crate::app::lyapunov::LyapunovMapJob;
use crate::app::sweep::FrameMap;
use crate::app::trajectory::TrajectoryJob;
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::store::MapStore;
use crate::render::{self, PictureSpec};
use crate::spec::{Grid, Precision, Range};

/// Requests waiting for (or holding) the engine at most; more get 503 at once, so a burst
/// of requests holds a bounded amount of memory.
pub const MAX_WAITING: usize = 64;

/// A request that has not finished in this time is cancelled (503).
pub const REQUEST_LIMIT: Duration = Duration::from_secs(60);

/// A connection must send a request's head within this time (from connecting, or from its
/// last answer on a kept-alive connection), else it is closed: a client that never finishes
/// its request does not hold its connection.
pub const HEADER_READ_LIMIT: Duration = Duration::from_secs(5);

/// Open connections at most; more are closed at once.
pub const MAX_CONNECTIONS: usize = 512;

/// Tiles and other computed answers kept, most recently used first (a 256^2 tile's PNG is
/// ~50-150 kB, so ~60 MB).
pub const CACHE_ENTRIES: usize = 512;

#[derive(Clone, Debug, PartialEq)]
pub struct ServeJob {
    pub host: IpAddr,
    /// 0: any free port (the URL says which).
    pub port: u16,
    /// The physics the page starts from and every request's defaults.
    pub base: ParamSources,
    pub backend: Backend,
    /// A Zarr store's map to show instead (its command fixes the physics): read from the
    /// store down to its own pixels, computed with its settings below them.
    pub store: Option<StoredMap>,
}

/// A store (`flip --data MAP.zarr`) and the map its command describes.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMap {
    pub path: PathBuf,
    pub command: String,
    pub map: FrameMap,
}

impl StoredMap {
    fn grid(&self) -> Grid {
        match self.map {
            FrameMap::Flip(s) => s.grid,
            FrameMap::Lyapunov(s) => s.grid,
        }
    }

    fn kind(&self) -> Kind {
        Kind::of(&self.map)
    }
}

/// The commands that reproduce what the page shows, written by the command line (the one
/// inverse of the flags).
#[derive(Clone, Copy)]
pub struct Commands {
    pub flip: fn(&FlipJob) -> String,
    pub lyapunov: fn(&LyapunovMapJob) -> String,
    pub trajectory: fn(&TrajectoryJob) -> String,
}

/// What the server says once it listens.
pub struct Ready {
    pub url: String,
    /// Where tiles are computed: the adapter's name or "the CPU".
    pub place: String,
    pub notices: Vec<String>,
}

/// How a session went, when it stops.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ServeSummary {
    pub url: String,
    /// Tiles computed, served from the cache, cancelled (their client left), refused (the
    /// queue was full).
    pub computed: u64,
    pub cached: u64,
    pub cancelled: u64,
    pub refused: u64,
}

#[derive(Default)]
struct Counters {
    computed: AtomicU64,
    cached: AtomicU64,
    cancelled: AtomicU64,
    refused: AtomicU64,
}

struct Shared {
    engine: Arc<tokio::sync::Mutex<Engine>>,
    place: String,
    has_f64: bool,
    cache: Mutex<LruCache<String, Bytes>>,
    waiting: AtomicUsize,
    counters: Counters,
    base: ParamSources,
    backend: Backend,
    commands: Commands,
    /// What the tiles cover: the whole turn, or the store's region.
    world: World,
    store: Option<(Arc<MapStore>, StoredMap)>,
}

impl Shared {
    fn stored(&self) -> Option<FrameMap> {
        self.store.as_ref().map(|(_, s)| s.map)
    }

    /// The view a query asks for (the store's, when serving one).
    fn view(&self, q: &mut Query) -> Result<View> {
        q.view(&self.base, self.stored())
    }

    /// The view of a query that holds nothing else.
    fn view_only(&self, q: HashMap<String, String>) -> Result<View> {
        let mut q = Query::new(q);
        let view = self.view(&mut q)?;
        q.finish()?;
        Ok(view)
    }
}

type S = Arc<Shared>;

/// Serves until `monitor` is cancelled (Ctrl-C); `ready` is told the URL once it listens.
pub fn run(
    job: &ServeJob,
    commands: Commands,
    monitor: &Monitor,
    ready: impl FnOnce(&Ready),
) -> Result<ServeSummary> {
    // The physics flags checked before anything starts.
    crate::spec::validate_params(&job.base.resolve()?)?;
    let store = match &job.store {
        Some(s) => Some((Arc::new(MapStore::open(&s.path)?), s.clone())),
        None => None,
    };
    let world = job
        .store
        .as_ref()
        .map_or(World::TURN, |s| World::of_grid(&s.grid()));
    let engine = Engine::new(job.backend)?;
    warm_up(&engine, &job.base.resolve()?, monitor)?;
    let info = engine.info();
    let shared = Arc::new(Shared {
        place: info.place().to_string(),
        has_f64: engine.has_f64(),
        engine: Arc::new(tokio::sync::Mutex::new(engine)),
        cache: Mutex::new(LruCache::new(
            NonZeroUsize::new(CACHE_ENTRIES).expect("nonzero"),
        )),
        waiting: AtomicUsize::new(0),
        counters: Counters::default(),
        base: job.base.clone(),
        backend: job.backend,
        commands,
        world,
        store,
    });
    let notices = shared
        .engine
        .try_lock()
        .map(|e| e.notices())
        .unwrap_or_default();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .max_blocking_threads(8)
        .enable_all()
        .build()?;
    let app = router(shared.clone());
    let url = runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind((job.host, job.port))
            .await
            .map_err(|e| {
                Error::invalid(
                    "port",
                    format!("cannot listen on {}:{}: {e}", job.host, job.port),
                )
            })?;
        let url = format!("http://{}/", listener.local_addr()?);
        ready(&Ready {
            url: url.clone(),
            place: shared.place.clone(),
            notices,
        });
        let stop = {
            let monitor = monitor.clone();
            async move {
                while !monitor.is_cancelled() {
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            }
        };
        tokio::select! {
            _ = serve_connections(listener, app) => {}
            _ = stop => {}
        }
        Ok::<String, Error>(url)
    })?;
    // Dropping the runtime drops every request, whose guards cancel their work.
    runtime.shutdown_timeout(Duration::from_secs(2));
    let c = &shared.counters;
    Ok(ServeSummary {
        url,
        computed: c.computed.load(Ordering::Relaxed),
        cached: c.cached.load(Ordering::Relaxed),
        cancelled: c.cancelled.load(Ordering::Relaxed),
        refused: c.refused.load(Ordering::Relaxed),
    })
}

/// Builds the flip kernel before the first request needs it (a tiny map), so the first view
/// waits only for its own tile.
fn warm_up(engine: &Engine, params: &crate::model::Params, monitor: &Monitor) -> Result<()> {
    let spec = crate::spec::FlipSpec::new(
        *params,
        Grid::square(8),
        crate::spec::Stepping {
            dt: 0.01,
            t_max: 0.1,
        },
    );
    engine.map(&spec, &monitor.quiet()).map(|_| ())
}

/// Accepts connections for ever: each served on its own task by HTTP/1 with
/// [`HEADER_READ_LIMIT`], at most [`MAX_CONNECTIONS`] at once.
async fn serve_connections(listener: tokio::net::TcpListener, app: Router) {
    let open = Arc::new(tokio::sync::Semaphore::new(MAX_CONNECTIONS));
    loop {
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            // Out of file descriptors and the like: wait, then go on.
            Err(_) => {
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(permit) = open.clone().try_acquire_owned() else {
            continue;
        };
        let service = hyper_util::service::TowerToHyperService::new(app.clone());
        tokio::spawn(async move {
            let _permit = permit;
            let mut http = hyper::server::conn::http1::Builder::new();
            http.timer(hyper_util::rt::TokioTimer::new())
                .header_read_timeout(HEADER_READ_LIMIT);
            let io = hyper_util::rt::TokioIo::new(stream);
            // A connection's errors (reset, timeout) end it and nothing else.
            let _ = http.serve_connection(io, service).await;
        });
    }
}

/// The routes; everything else is 404.
fn router(shared: S) -> Router {
    Router::new()
        .route("/", get(|| async { assets::page() }))
        .route("/assets/{*path}", get(asset))
        .route("/tile/{z}/{x}/{y}", get(tile))
        .route("/api/info", get(info))
        .route("/api/point", get(point))
        .route("/api/trajectory", get(trajectory))
        .route("/api/range", get(range))
        .route("/api/save", get(save))
        .route("/api/legend", get(legend))
        .route("/api/stats", get(stats))
        .fallback(|| async { (StatusCode::NOT_FOUND, "not found\n") })
        .with_state(shared)
}

async fn asset(Path(path): Path<String>) -> Response {
    assets::get(&path)
}

type Params = AxumQuery<HashMap<String, String>>;

/// An error as the page sees it: invalid values 400 with the key and the reason, a full
/// queue or a request past its time 503, the rest 500.
fn reply(e: Error) -> Response {
    match e {
        Error::InvalidSpec { .. } => (StatusCode::BAD_REQUEST, format!("{e}\n")).into_response(),
        Error::Interrupted => {
            (StatusCode::SERVICE_UNAVAILABLE, "cancelled\n".to_string()).into_response()
        }
        e => (StatusCode::INTERNAL_SERVER_ERROR, format!("{e}\n")).into_response(),
    }
}

fn busy(why: &str) -> Response {
    (
        StatusCode::SERVICE_UNAVAILABLE,
        [(header::RETRY_AFTER, "1")],
        format!("{why}\n"),
    )
        .into_response()
}

/// Sets the request's cancel flag when the request is dropped before its work finished
/// (the client went away, or the server stops), and counts it.
struct CancelOnDrop {
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
async fn on_engine<T: Send + 'static>(
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

fn cached(shared: &S, key: &str) -> Option<Bytes> {
    let hit = shared.cache.lock().ok()?.get(key).cloned();
    if hit.is_some() {
        shared.counters.cached.fetch_add(1, Ordering::Relaxed);
    }
    hit
}

fn remember(shared: &S, key: String, bytes: Bytes) {
    if let Ok(mut c) = shared.cache.lock() {
        c.put(key, bytes);
    }
}

/// A tile's answer (bytes shared with the cache, not copied).
fn png(bytes: Bytes, precision: &str) -> Response {
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

/// Where a map over `grid` runs and in which precision, in words ("f32", "f64").
fn precision_of(engine: &Engine, grid: &Grid, asked: Precision) -> &'static str {
    engine.map_info(grid, asked).path.precision().name()
}

/// The tile (z, x, y), as the bare PNG `chaoscope flip` / `lyapunov` would make of it.
async fn tile(
    AxumState(shared): AxumState<S>,
    Path((z, x, y)): Path<(String, String, String)>,
    AxumQuery(q): Params,
) -> Response {
    type Tile = (View, Grid, String, (u32, u64, u64));
    let parsed = (|| -> Result<Tile> {
        let int = |key: &'static str, s: &str| {
            s.parse::<u64>()
                .map_err(|_| Error::invalid(key, format!("{s:?} is not a tile index")))
        };
        let y = y.strip_suffix(".png").unwrap_or(&y);
        let (z, x, y) = (int("z", &z)?, int("x", &x)?, int("y", y)?);
        let mut q = Query::new(q);
        let view = shared.view(&mut q)?;
        let size = q
            .count("size", view::TILE_SIZES.0, view::TILE_SIZES.1)?
            .unwrap_or(256);
        q.finish()?;
        if let Some((_, stored)) = &shared.store
            && view.kind != stored.kind()
            && view.kind != Kind::Resolved
        {
            return Err(Error::invalid(
                "kind",
                format!("the store holds a {:?} map", stored.kind()).to_lowercase(),
            ));
        }
        let z = u32::try_from(z).unwrap_or(u32::MAX);
        let grid = shared.world.tile_grid(z, x, y, size)?;
        let key = format!("tile {z}/{x}/{y}/{size} {view:?}");
        Ok((view, grid, key, (z, x, y)))
    })();
    let (view, grid, key, (z, x, y)) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    if let Some(bytes) = cached(&shared, &key) {
        return png(bytes, "cached");
    }
    let (world, store) = (shared.world, shared.store.clone());
    let result = on_engine(&shared, move |engine, monitor| {
        let (rgb, precision) = match store {
            Some((store, _)) if z <= world.native => {
                let at = StoredTile {
                    world,
                    z,
                    x,
                    y,
                    size: grid.width,
                };
                (stored_rgb(&store, &at, &view, grid)?, "stored")
            }
            _ => tile_rgb(engine, &view, grid, monitor)?,
        };
        let bytes = render::png_bytes(grid.width, grid.height, &rgb, &[])?;
        Ok((Bytes::from(bytes), precision))
    })
    .await;
    match result {
        Ok((bytes, precision)) => {
            shared.counters.computed.fetch_add(1, Ordering::Relaxed);
            remember(&shared, key, bytes.clone());
            png(bytes, precision)
        }
        Err(r) => r,
    }
}

/// The RGB bytes of a view over `grid` (bare, one pixel a pendulum) and the precision it ran
/// in.
pub fn tile_rgb(
    engine: &Engine,
    view: &View,
    grid: Grid,
    monitor: &Monitor,
) -> Result<(Vec<u8>, &'static str)> {
    let picture = PictureSpec {
        annotate: false,
        colormap: view.colormap,
    };
    match view.kind {
        Kind::Flip | Kind::FlipKind | Kind::Resolved => {
            let spec = view.flip_spec(grid);
            spec.validate()?;
            let precision = engine.plan(&spec)?.path.precision().name();
            let verdict = view.unresolved || view.kind == Kind::Resolved;
            let (field, mask) = super::map_and_verdict(engine, &spec, verdict, monitor)?;
            let rgb = match (view.kind, mask) {
                (Kind::Resolved, Some(mask)) => mask_rgb(&mask),
                (_, mask) => {
                    let shown = mask.as_deref().filter(|_| view.unresolved);
                    render::flip_picture(&field, &spec, &picture, shown)?.rgb
                }
            };
            Ok((rgb, precision))
        }
        Kind::Ftle => {
            let spec = view.lyapunov_spec(grid);
            spec.validate()?;
            let (field, mask) = super::map_and_verdict(engine, &spec, view.unresolved, monitor)?;
            let rgb =
                render::lyapunov_picture(&field, &spec, view.range, &picture, mask.as_deref())?.rgb;
            Ok((rgb, precision_of(engine, &grid, spec.precision)))
        }
    }
}

/// Where a tile lies on a stored map's region.
struct StoredTile {
    world: World,
    z: u32,
    x: u64,
    y: u64,
    size: u32,
}

/// The colour of tile pixels beyond a stored map's edge (the page's background).
const OUTSIDE_RGB: [u8; 3] = [42, 42, 48];

/// A tile at or above the store's own level: its pixels read from the store (the stored
/// pixel under each tile pixel's centre), coloured as `chaoscope render` colours them.
fn stored_rgb(store: &MapStore, at: &StoredTile, view: &View, grid: Grid) -> Result<Vec<u8>> {
    let size = at.size as usize;
    let (width, height) = (at.world.width as u64, at.world.height as u64);
    let cols: Vec<u64> = (0..at.size)
        .map(|i| at.world.stored_pixel(at.z, at.x, i, at.size))
        .collect();
    let verdict = view.unresolved || view.kind == Kind::Resolved;
    let mut field = Field::new(at.size, at.size, f32::NAN);
    let mut mask = vec![255u8; size * size];
    let mut outside = vec![false; size * size];
    let mut row_read: Option<(u64, Vec<f32>, Option<Vec<u8>>)> = None;
    for j in 0..size {
        let row = at.world.stored_pixel(at.z, at.y, j as u32, at.size);
        if row >= height {
            outside[j * size..(j + 1) * size].fill(true);
            continue;
        }
        if row_read.as_ref().is_none_or(|(r, _, _)| *r != row) {
            let values = store.read_rows(row as u32, 1)?;
            let resolved = match verdict {
                true => Some(store.read_resolved(row as u32, 1)?.ok_or_else(|| {
                    Error::invalid(
                        "kind",
                        "the store has no verdict (make it with --resolved MAP.zarr)",
                    )
                })?),
                false => None,
            };
            row_read = Some((row, values, resolved));
        }
        let (_, values, resolved) = row_read.as_ref().expect("read above");
        for (i, &col) in cols.iter().enumerate() {
            let k = j * size + i;
            if col >= width {
                outside[k] = true;
                continue;
            }
            field.data[k] = values[col as usize];
            if let Some(r) = resolved {
                mask[k] = r[col as usize];
            }
        }
    }
    let picture = PictureSpec {
        annotate: false,
        colormap: view.colormap,
    };
    let shown = Some(mask.as_slice()).filter(|_| view.unresolved);
    let mut rgb = match view.kind {
        Kind::Resolved => mask_rgb(&mask),
        Kind::Flip | Kind::FlipKind => {
            render::flip_picture(&field, &view.flip_spec(grid), &picture, shown)?.rgb
        }
        Kind::Ftle => {
            let spec = view.lyapunov_spec(grid);
            render::lyapunov_picture(&field, &spec, view.range, &picture, shown)?.rgb
        }
    };
    for (px, _) in rgb.chunks_exact_mut(3).zip(&outside).filter(|(_, o)| **o) {
        px.copy_from_slice(&OUTSIDE_RGB);
    }
    Ok(rgb)
}

/// The verdict as a picture: white resolved, black not.
pub fn mask_rgb(mask: &[u8]) -> Vec<u8> {
    mask.iter()
        .flat_map(|&m| [if m == 1 { 255 } else { 0 }; 3])
        .collect()
}

fn json(value: serde_json::Value) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        value.to_string(),
    )
        .into_response()
}

/// What the page needs to know first: where tiles run, the limits, the starting physics.
async fn info(AxumState(shared): AxumState<S>) -> Response {
    let p = match shared.base.resolve() {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let colormaps: Vec<&str> = render::Colormap::ALL.iter().map(|c| c.name()).collect();
    let w = shared.world;
    let (units_across, units_down) = w.units();
    let store = shared.store.as_ref().map(|(_, s)| {
        serde_json::json!({
            "name": s.path.file_name().map(|n| n.to_string_lossy().into_owned()),
            "command": s.command,
            "kind": s.kind(),
            "width": w.width,
            "height": w.height,
        })
    });
    let stepping = shared.stored().map(|m| match m {
        FrameMap::Flip(s) => s.stepping,
        FrameMap::Lyapunov(s) => s.stepping,
    });
    let p = match shared.stored() {
        Some(FrameMap::Flip(s)) => s.params,
        Some(FrameMap::Lyapunov(s)) => s.params,
        None => p,
    };
    json(serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "place": shared.place,
        "has_f64": shared.has_f64,
        "f32_min_pixel_step": crate::spec::F32_MIN_PIXEL_STEP,
        "f64_min_pixel_step": crate::spec::F64_MIN_PIXEL_STEP,
        "max_zoom": view::MAX_ZOOM,
        "max_t_max": view::MAX_T_MAX,
        "kinds": Kind::NAMES,
        "colormaps": colormaps,
        "defaults": {
            "m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "g": p.g,
            "damping": p.losses.joint1,
            "t_max": stepping.map_or(20.0, |s| s.t_max),
            "dt": stepping.map_or(0.01, |s| s.dt),
        },
        "world": {
            "theta1": [w.theta1.min, w.theta1.max],
            "theta2": [w.theta2.min, w.theta2.max],
            "units": [units_across, units_down],
            "native": w.native,
        },
        "store": store,
    }))
}

/// A clicked pixel: its flip time as the map computes it (a one-pixel map `pixel` rad wide
/// around the start, so it runs in the tile's precision) and whether it is resolved.
async fn point(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<(View, Grid)> {
        let mut q = Query::new(q);
        let mut view = shared.view(&mut q)?;
        view.kind = Kind::Flip;
        let start = view::start(&mut q)?;
        let pixel = q.within("pixel", 1e-16, 1.0)?.unwrap_or(1e-3);
        q.finish()?;
        let around = |x: f64| Range {
            min: x - 0.5 * pixel,
            max: x + 0.5 * pixel,
        };
        let grid = Grid {
            width: 1,
            height: 1,
            theta1: around(start.theta1),
            theta2: around(start.theta2),
            omega1: 0.0,
            omega2: 0.0,
        };
        Ok((view, grid))
    })();
    let (view, grid) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let t_max = view.stepping.t_max;
    let result = on_engine(&shared, move |engine, monitor| {
        let spec = view.flip_spec(grid);
        spec.validate()?;
        let (field, mask) = super::map_and_verdict(engine, &spec, true, monitor)?;
        let resolved = mask.is_some_and(|m| m[0] == 1);
        Ok((field, resolved, precision_of(engine, &grid, spec.precision)))
    })
    .await;
    match result {
        Ok((field, resolved, precision)) => {
            let time = {
                let t = field.data[0];
                match t.is_finite() {
                    true => serde_json::json!(t),
                    false if t.is_nan() => serde_json::json!("nan"),
                    false => serde_json::json!("never"),
                }
            };
            json(serde_json::json!({
                "theta1": grid.theta1_at(0),
                "theta2": grid.theta2_at(0),
                "flip_time": time,
                "resolved": resolved,
                "precision": precision,
                "t_max": t_max,
            }))
        }
        Err(r) => r,
    }
}

/// One start's trajectory: exactly the CSV `chaoscope trajectory` writes (CPU f64, a row
/// every ~0.02 s), its reproducing command on the first line.
async fn trajectory(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<TrajectoryJob> {
        let mut q = Query::new(q);
        let view = shared.view(&mut q)?;
        let start = view::start(&mut q)?;
        q.finish()?;
        let dt = view.stepping.dt;
        let stride = (0.02 / dt).round().max(1.0);
        Ok(TrajectoryJob {
            params: view.params,
            start,
            stepping: view.stepping,
            every: Some(stride * dt),
            backend: Backend::Cpu,
            precision: Precision::F32,
            output: None,
        })
    })();
    let job = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let command = (shared.commands.trajectory)(&job);
    let work = tokio::task::spawn_blocking(move || {
        let mut csv = Vec::new();
        crate::app::trajectory::run(&job, command, &Monitor::hidden(), &mut csv).map(|_| csv)
    });
    match tokio::time::timeout(REQUEST_LIMIT, work).await {
        Ok(Ok(Ok(csv))) => ([(header::CONTENT_TYPE, "text/csv")], csv).into_response(),
        Ok(Ok(Err(e))) => reply(e),
        Ok(Err(e)) => reply(Error::Format(format!("the trajectory failed: {e}"))),
        Err(_) => busy("the request took too long"),
    }
}

/// The divergence map's colour range for the page's physics: 0 to the 99.5th percentile of
/// the whole turn's exponents (a 128^2 overview), as `chaoscope lyapunov` picks it.
async fn range(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let view = match shared.view_only(q) {
        Ok(v) => v,
        Err(e) => return reply(e),
    };
    let key = format!(
        "range {:?} {:?} {:?}",
        view.params, view.stepping, view.accurate
    );
    if let Some(bytes) = cached(&shared, &key) {
        return json(serde_json::from_slice(&bytes).unwrap_or_default());
    }
    let world = shared.world;
    let result = on_engine(&shared, move |engine, monitor| {
        let spec = view.lyapunov_spec(Grid {
            theta1: world.theta1,
            theta2: world.theta2,
            ..Grid::square(128)
        });
        spec.validate()?;
        Ok(render::ftle_range(&engine.map(&spec, monitor)?))
    })
    .await;
    match result {
        Ok((lo, hi)) => {
            let value = serde_json::json!({ "lo": lo, "hi": hi });
            remember(&shared, key, Bytes::from(value.to_string()));
            json(value)
        }
        Err(r) => r,
    }
}

/// The view as a PNG file made by `chaoscope flip` / `lyapunov`'s own run (its command in
/// the metadata), over the region and at the size asked.
async fn save(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<(View, Grid, bool)> {
        let mut q = Query::new(q);
        let view = shared.view(&mut q)?;
        let grid = view::region_grid(&mut q)?;
        let annotate = q.flag("annotate")?;
        q.finish()?;
        Ok((view, grid, annotate))
    })();
    let (view, grid, annotate) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let (backend, commands) = (shared.backend, shared.commands);
    let result = on_engine(&shared, move |_engine, monitor| {
        let dir = tempfile::tempdir()?;
        let files = MapOutputs {
            output: dir.path().join("view.png"),
            data: None,
            resolved: None,
            show_unresolved: view.unresolved || view.kind == Kind::Resolved,
        };
        let picture = PictureSpec {
            annotate,
            colormap: view.colormap,
        };
        let name = match view.kind {
            Kind::Flip | Kind::FlipKind | Kind::Resolved => {
                let job = FlipJob {
                    spec: view.flip_spec(grid),
                    backend,
                    picture,
                    files: files.clone(),
                    tile: None,
                };
                crate::app::flip::run(&job, (commands.flip)(&job), monitor)?;
                "chaoscope-flip.png"
            }
            Kind::Ftle => {
                let job = LyapunovMapJob {
                    spec: view.lyapunov_spec(grid),
                    backend,
                    picture,
                    files: files.clone(),
                    tile: None,
                    colour_range: Some(view.range),
                };
                crate::app::lyapunov::run_map(&job, (commands.lyapunov)(&job), monitor)?;
                "chaoscope-lyapunov.png"
            }
        };
        let bytes = std::fs::read(&files.output).map_err(|e| Error::File {
            path: files.output.clone(),
            source: e,
        })?;
        Ok((bytes, name))
    })
    .await;
    match result {
        Ok((bytes, name)) => (
            [
                (header::CONTENT_TYPE, "image/png".to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    format!("attachment; filename=\"{name}\""),
                ),
            ],
            bytes,
        )
            .into_response(),
        Err(r) => r,
    }
}

/// The colour bar of a view, from the tables the tiles are coloured with: colours from left
/// to right (early to late flips; regular to chaotic exponents), ticks as (fraction, label),
/// and the colours of never, NaN and unresolved pixels.
async fn legend(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let view = match shared.view_only(q) {
        Ok(v) => v,
        Err(e) => return reply(e),
    };
    let (colors, ticks, label) = match view.kind {
        Kind::Ftle => {
            let (lo, hi) = (view.range.0 as f64, view.range.1 as f64);
            let ticks: Vec<(f64, String)> = render::decimal_ticks(lo, hi)
                .into_iter()
                .map(|(v, l)| ((v - lo) / (hi - lo), l))
                .collect();
            let table = render::ftle_table(view.colormap.unwrap_or(render::Colormap::Magma));
            (table, ticks, "FTLE (1/s)")
        }
        Kind::FlipKind => {
            let (colors, ticks) = render::flip_kind_bar();
            (colors, ticks, "first flip")
        }
        Kind::Flip | Kind::Resolved => {
            let colors = render::FlipColors {
                t_lo: (view.params.l1 / view.params.g).sqrt(),
                t_max: view.stepping.t_max,
                colormap: view.colormap.unwrap_or(render::Colormap::Inferno),
            };
            // The bar runs late to early; the page reads left to right from early.
            let (mut table, ticks) = colors.bar();
            table.reverse();
            let ticks = ticks.into_iter().map(|(f, l)| (1.0 - f, l)).collect();
            (table, ticks, "flip time (s)")
        }
    };
    let every = (colors.len() / 64).max(1);
    let colors: Vec<[u8; 3]> = colors.into_iter().step_by(every).collect();
    json(serde_json::json!({
        "label": label,
        "colors": colors,
        "ticks": ticks,
        "never": render::NEVER_RGB,
        "nan": render::NAN_RGB,
        "unresolved": render::UNRESOLVED_RGB,
    }))
}

/// Counters since the start, and the queue now.
async fn stats(AxumState(shared): AxumState<S>) -> Response {
    let c = &shared.counters;
    json(serde_json::json!({
        "computed": c.computed.load(Ordering::Relaxed),
        "cached": c.cached.load(Ordering::Relaxed),
        "cancelled": c.cancelled.load(Ordering::Relaxed),
        "refused": c.refused.load(Ordering::Relaxed),
        "waiting": shared.waiting.load(Ordering::Relaxed),
        "cache_entries": shared.cache.lock().map(|c| c.len()).unwrap_or(0),
    }))
}
