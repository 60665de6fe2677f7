//! `serve`: the explorer. A local HTTP server (axum on tokio) whose page (Leaflet, vendored)
//! shows flip, divergence and verdict maps as tiles computed on demand by the one engine,
//! and a clicked pixel's pendulum. Every tile is a pure function of its URL, so tiles are
//! cached by URL; requests wait for the engine in a bounded queue, and a request whose client
//! went away is cancelled at the engine's next dispatch.

mod answers;
mod api;
mod assets;
mod kind;
mod query;
mod tiles;
pub mod view;
pub mod world;

use self::api::{info, point, range, save, stats, trajectory, zoom};
use self::tiles::{legend, tile};
pub use self::tiles::{mask_rgb, tile_rgb};

use std::net::IpAddr;
use std::num::NonZeroUsize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::body::Bytes;
use axum::extract::{Path, Query as AxumQuery, State};
use axum::http::StatusCode;
use axum::response::{Redirect, Response};
use axum::routing::get;
use lru::LruCache;

use self::view::{Kind, Query, View};
use self::world::World;
use crate::app::flip::FlipJob;
use crate::app::lyapunov::LyapunovMapJob;
use crate::app::trajectory::TrajectoryJob;
use crate::engine::{Backend, Engine};
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::params::ParamSources;
use crate::render::store::MapStore;
use crate::spec::AnyMap;
use crate::spec::{Grid, MapSpec};

/// Requests waiting for (or holding) the engine at most; more get 503 at once, so a burst
/// of requests holds a bounded amount of memory.
pub const MAX_WAITING: usize = 64;

/// A request that has not finished in this time is cancelled (503).
pub const REQUEST_LIMIT: Duration = Duration::from_secs(60);

/// A connection must send a request's head within this time (from connecting, or from its
/// last answer on a kept-alive connection), else it is closed: a client that never finishes
/// its request does not hold its connection.
pub const HEADER_READ_LIMIT: Duration = Duration::from_secs(5);

/// A request's head (request line and headers) may take this many bytes at most (the page's
/// longest is under 2 kB); a larger one is answered 431 and its connection closed.
pub const MAX_HEAD_BYTES: usize = 16 << 10;

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
    /// The static explorer (`chaoscope web`'s site), served under /web/: it computes on the
    /// viewer's GPU, and falls back to this server's explorer where the browser has no WebGPU.
    pub site: crate::web::SiteSpec,
}

/// A store (`flip --data MAP.zarr`) and the map its command describes.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMap {
    pub path: PathBuf,
    pub command: String,
    pub map: AnyMap,
}

impl StoredMap {
    fn grid(&self) -> Grid {
        *self.map.grid()
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
    pub zoom_flip: fn(&crate::app::zoom::ZoomJob<crate::spec::FlipSpec>) -> String,
    pub zoom_lyapunov: fn(&crate::app::zoom::ZoomJob<crate::spec::LyapunovSpec>) -> String,
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
    /// Whether the engine has a GPU (a view's defaults that depend on the path).
    on_gpu: bool,
    cache: Mutex<LruCache<String, Bytes>>,
    waiting: AtomicUsize,
    counters: Counters,
    base: ParamSources,
    backend: Backend,
    commands: Commands,
    /// What a store's tiles cover (a view's plane otherwise).
    store_world: Option<World>,
    store: Option<(Arc<MapStore>, StoredMap)>,
    /// The static explorer's files, by name (shared by every answer, not copied).
    site: Vec<(String, Bytes)>,
}

impl Shared {
    fn stored(&self) -> Option<AnyMap> {
        self.store.as_ref().map(|(_, s)| s.map)
    }

    /// The view a query asks for (the store's, when serving one).
    fn view(&self, q: &mut Query) -> Result<View> {
        q.view(&self.base, self.stored(), self.on_gpu)
    }

    /// What a view's tiles cover: the store's region, or the view's plane.
    fn world(&self, view: &View) -> World {
        self.store_world
            .unwrap_or_else(|| World::of_plane(&view.plane))
    }

    /// The view of a query that holds nothing else.
    fn view_only(&self, q: Vec<(String, String)>) -> Result<View> {
        let mut q = Query::new(q)?;
        let view = self.view(&mut q)?;
        q.finish()?;
        Ok(view)
    }
}

type S = Arc<Shared>;

/// Serves on `engine` (the door's, kept for the explorer's life) until `monitor` is cancelled
/// (Ctrl-C); `ready` is told the URL once it listens.
pub fn run(
    job: &ServeJob,
    engine: Engine,
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
    let store_world = job.store.as_ref().map(|s| World::of_grid(&s.grid()));
    warm_up(&engine, &job.base.resolve()?, monitor)?;
    let info = engine.info();
    let shared = Arc::new(Shared {
        place: info.place().to_string(),
        has_f64: engine.has_f64(),
        on_gpu: engine.gpu().is_some(),
        engine: Arc::new(tokio::sync::Mutex::new(engine)),
        cache: Mutex::new(LruCache::new(
            NonZeroUsize::new(CACHE_ENTRIES).expect("nonzero"),
        )),
        waiting: AtomicUsize::new(0),
        counters: Counters::default(),
        base: job.base.clone(),
        backend: job.backend,
        commands,
        store_world,
        store,
        site: crate::web::files(&job.site)
            .into_iter()
            .map(|(name, bytes)| (name, Bytes::from(bytes)))
            .collect(),
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
                .header_read_timeout(HEADER_READ_LIMIT)
                .max_buf_size(MAX_HEAD_BYTES);
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
        .route("/web", get(|| async { Redirect::permanent("/web/") }))
        .route(
            "/web/",
            get(|State(s): State<S>| async move { assets::site_file(&s.site, "index.html") }),
        )
        .route("/web/{*path}", get(web_file))
        .route("/tile/{z}/{x}/{y}", get(tile))
        .route("/api/info", get(info))
        .route("/api/point", get(point))
        .route("/api/trajectory", get(trajectory))
        .route("/api/range", get(range))
        .route("/api/save", get(save))
        .route("/api/zoom", get(zoom))
        .route("/api/legend", get(legend))
        .route("/api/stats", get(stats))
        .fallback(|| async { (StatusCode::NOT_FOUND, "not found\n") })
        .with_state(shared)
}

async fn asset(Path(path): Path<String>) -> Response {
    assets::get(&path)
}

async fn web_file(State(s): State<S>, Path(path): Path<String>) -> Response {
    assets::site_file(&s.site, &path)
}

type Params = AxumQuery<Vec<(String, String)>>;
