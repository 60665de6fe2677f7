//! The page's other questions: what the server runs, a clicked pixel, its trajectory, the
//! divergence colour range, a saved view, the counters.

use super::answers::{busy, cached, json, on_engine, remember, reply};
use super::tiles::planned;
use super::{Kind, Params, Query, REQUEST_LIMIT, S, View, World, view};
use crate::app::MapOutputs;
use crate::app::film::FilmSpec;
use crate::app::flip::FlipJob;
use crate::app::lyapunov::LyapunovMapJob;
use crate::app::trajectory::TrajectoryJob;
use crate::app::zoom::{Target, ZoomJob};
use crate::engine::Backend;
use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::{self, PictureSpec};
use crate::spec::{Grid, MapSpec, Precision};
use axum::body::Bytes;
use axum::extract::{Query as AxumQuery, State as AxumState};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use std::sync::atomic::Ordering;

/// What the page needs to know first: where tiles run, the limits, the starting physics.
pub(super) async fn info(AxumState(shared): AxumState<S>) -> Response {
    let p = match shared.base.resolve() {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let colormaps: Vec<&str> = render::Colormap::ALL.iter().map(|c| c.name()).collect();
    let axis = |a: &crate::spec::Axis| serde_json::json!({"name": a.var.name(), "range": [a.range.min, a.range.max]});
    let store = shared.store.as_ref().map(|(_, s)| {
        let w = World::of_grid(&s.grid());
        let f = w.plane.fixed;
        serde_json::json!({
            "name": s.path.file_name().map(|n| n.to_string_lossy().into_owned()),
            "command": s.command,
            "kind": s.kind(),
            "width": w.plane.width,
            "height": w.plane.height,
            "x": axis(&w.plane.x),
            "y": axis(&w.plane.y),
            "start": {"theta1": f.theta1, "omega1": f.omega1, "theta2": f.theta2, "omega2": f.omega2},
            "units": w.units(),
            "native": w.native,
        })
    });
    // What an axis may vary: the page's axis menus.
    let vars: Vec<_> = crate::spec::Var::ALL
        .iter()
        .map(|v| {
            let r = v.default_range();
            serde_json::json!({
                "name": v.name(), "symbol": v.symbol(), "unit": v.unit(),
                "range": [r.min, r.max], "angle": v.is_angle(), "state": v.is_state(),
                "writes": v.writes(),
            })
        })
        .collect();
    let stepping = shared.stored().map(|m| m.stepping());
    let p = shared.stored().map_or(p, |m| m.params());
    json(serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "place": shared.place,
        "has_f64": shared.has_f64,
        // The precisions' epsilons, for the page's finest steps (assets/rules.js).
        "f32_epsilon": f32::EPSILON,
        "f64_epsilon": f64::EPSILON,
        "max_zoom": view::MAX_ZOOM,
        "max_t_max": view::MAX_T_MAX,
        "kinds": Kind::all().map(Kind::describe).collect::<Vec<_>>(),
        "colormaps": colormaps,
        "defaults": {
            "m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "g": p.g,
            "damping": p.losses.joint1,
            "t_max": stepping.map_or(20.0, |s| s.t_max),
            "dt": stepping.map_or(0.01, |s| s.dt),
        },
        "vars": vars,
        "store": store,
    }))
}

/// A clicked pixel (`px`, `py` along the view's axes): its flip time as the map computes it
/// (a one-pixel map `pixel` x `pixel_y` wide around it, so it runs in the tile's precision),
/// whether it is resolved, and its pendulum.
pub(super) async fn point(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<(View, Grid, Pendulum)> {
        let mut q = Query::new(q)?;
        let mut view = shared.view(&mut q)?;
        view.kind = Kind::FLIP;
        let (grid, pendulum) = view::point(&mut q, &view)?;
        q.finish()?;
        Ok((view, grid, pendulum))
    })();
    let (view, grid, (p, s)) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let t_max = view.stepping.t_max;
    let result = on_engine(&shared, move |engine, monitor| {
        let spec = view.flip_spec(grid);
        spec.validate()?;
        let (field, mask, precision) = planned(engine, &spec, true, monitor)?;
        let resolved = mask.is_some_and(|m| m[0] == 1);
        Ok((field, resolved, precision))
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
                "x": grid.x.var.get(&p, &s),
                "y": grid.y.var.get(&p, &s),
                "start": {"theta1": s.theta1, "omega1": s.omega1, "theta2": s.theta2, "omega2": s.omega2},
                "params": {"m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "g": p.g},
                "flip_time": time,
                "resolved": resolved,
                "precision": precision,
                "t_max": t_max,
            }))
        }
        Err(r) => r,
    }
}

type Pendulum = (crate::model::Params, crate::model::State);

/// One start's trajectory: exactly the CSV `chaoscope trajectory` writes (CPU f64, a row
/// every ~0.02 s), its reproducing command on the first line.
pub(super) async fn trajectory(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<TrajectoryJob> {
        let mut q = Query::new(q)?;
        let view = shared.view(&mut q)?;
        let (_, (params, start)) = view::point(&mut q, &view)?;
        q.finish()?;
        let dt = view.stepping.dt;
        let stride = (0.02 / dt).round().max(1.0);
        Ok(TrajectoryJob {
            params,
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
        // A single run on the CPU: an engine without a device, made per request.
        let engine = crate::engine::Engine::new(Backend::Cpu)?;
        crate::app::trajectory::run(
            &job,
            &crate::app::Running::new(&engine, command, &Monitor::hidden()),
            &mut csv,
        )
        .map(|_| csv)
    });
    match tokio::time::timeout(REQUEST_LIMIT, work).await {
        Ok(Ok(Ok(csv))) => ([(header::CONTENT_TYPE, "text/csv")], csv).into_response(),
        Ok(Ok(Err(e))) => reply(e),
        Ok(Err(e)) => reply(Error::Format(format!("the trajectory failed: {e}"))),
        Err(_) => busy("the request took too long"),
    }
}

/// A divergence-family map's colour range for the page's physics and kind: its default
/// (render::default_range) over the view's region (a 128^2 overview), as `chaoscope lyapunov`
/// picks it.
pub(super) async fn range(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let view = match shared.view_only(q) {
        Ok(v) => v,
        Err(e) => return reply(e),
    };
    let world = shared.world(&view);
    let key = format!(
        "range {:?} {:?} {:?} {:?} {:?}",
        view.kind, view.params, view.stepping, view.accurate, world.plane
    );
    if let Some(bytes) = cached(&shared, &key) {
        return json(serde_json::from_slice(&bytes).unwrap_or_default());
    }
    let result = on_engine(&shared, move |engine, monitor| {
        let overview = Grid {
            width: 128,
            height: 128,
            ..world.plane
        };
        let spec = view.lyapunov_spec(overview);
        spec.validate()?;
        let (field, _, _) = planned(engine, &spec, false, monitor)?;
        Ok(render::default_range(&spec, &field))
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
pub(super) async fn save(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<(View, Grid, bool)> {
        let mut q = Query::new(q)?;
        let view = shared.view(&mut q)?;
        let grid = view::region_grid(&mut q, &view)?;
        let annotate = q.flag("annotate")?;
        q.finish()?;
        Ok((view, grid, annotate))
    })();
    let (view, grid, annotate) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let (backend, commands) = (shared.backend, shared.commands);
    let result = on_engine(&shared, move |engine, monitor| {
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
            Kind::FLIP | Kind::FLIP_KIND | Kind::Resolved => {
                let job = FlipJob {
                    spec: view.flip_spec(grid),
                    backend,
                    picture,
                    files: files.clone(),
                    tile: None,
                    colour_range: None,
                    samples: 1,
                };
                crate::app::flip::run(
                    &job,
                    &crate::app::Running::new(engine, (commands.flip)(&job), monitor),
                )?;
                "chaoscope-flip.png"
            }
            Kind::Map(_) => {
                let job = LyapunovMapJob {
                    spec: view.lyapunov_spec(grid),
                    backend,
                    picture,
                    files: files.clone(),
                    tile: None,
                    colour_range: Some(view.range),
                    samples: 1,
                };
                crate::app::lyapunov::run_map(
                    &job,
                    &crate::app::Running::new(engine, (commands.lyapunov)(&job), monitor),
                )?;
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

/// "Zoom film to here": the command of a zoom from the whole plane (`width` x `height`
/// pixels) to the view centred at (`cx`, `cy`), `w` wide along x, over `frames` frames,
/// planned as `chaoscope zoom` plans it (a view past f64 is refused as it refuses it).
pub(super) async fn zoom(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let parsed = (|| -> Result<(View, Grid, Target, u32)> {
        let mut q = Query::new(q)?;
        let view = shared.view(&mut q)?;
        if view.stored.is_some() {
            return Err(Error::invalid(
                "kind",
                "a zoom computes every frame: it starts from a plane, not a store",
            ));
        }
        let grid = view::region_grid(&mut q, &view)?;
        let mut value = |key| {
            q.within(key, -1e6, 1e6)?
                .ok_or_else(|| Error::invalid(key, "is needed (the view to zoom to)"))
        };
        let (x, y) = (value("cx")?, value("cy")?);
        let width = q
            .within("w", 1e-300, 1e6)?
            .ok_or_else(|| Error::invalid("w", "is needed (the width to zoom to)"))?;
        let frames = q
            .count("frames", 2, 100_000)?
            .unwrap_or(crate::spec::ZOOM.frames);
        q.finish()?;
        Ok((view, grid, Target { x, y, width }, frames))
    })();
    let (view, grid, to, frames) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    let (backend, commands) = (shared.backend, shared.commands);
    // Checked by its views alone, off the engine: a plan never holds the engine a tile needs.
    let result = tokio::task::spawn_blocking(move || -> Result<String> {
        let output = std::path::PathBuf::from(crate::spec::ZOOM.output);
        let film = FilmSpec {
            path: output.join(crate::app::zoom::FILM),
            fps: crate::spec::ZOOM.fps,
            crf: crate::spec::ZOOM.crf,
        };
        let files = MapOutputs {
            output: output.join("frame.png"),
            data: None,
            resolved: None,
            show_unresolved: view.unresolved || view.kind == Kind::Resolved,
        };
        fn of<M>(
            map: crate::app::map::MapJob<M>,
            to: Target,
            frames: u32,
            film: &FilmSpec,
        ) -> ZoomJob<M> {
            ZoomJob {
                map,
                to: vec![to],
                frames,
                film: film.clone(),
                output: std::path::PathBuf::from(crate::spec::ZOOM.output),
                tile: None,
                verdict: false,
            }
        }
        let picture = PictureSpec {
            annotate: false,
            colormap: view.colormap,
        };
        match view.kind {
            Kind::FLIP | Kind::FLIP_KIND | Kind::Resolved => {
                let job = of(
                    FlipJob {
                        spec: view.flip_spec(grid),
                        backend,
                        picture,
                        files,
                        tile: None,
                        colour_range: None,
                        samples: 1,
                    },
                    to,
                    frames,
                    &film,
                );
                crate::app::zoom::check(&job).map_err(|e| e.renamed("to", "w"))?;
                Ok((commands.zoom_flip)(&job))
            }
            Kind::Map(_) => {
                let job = of(
                    LyapunovMapJob {
                        spec: view.lyapunov_spec(grid),
                        backend,
                        picture,
                        files,
                        tile: None,
                        colour_range: Some(view.range),
                        samples: 1,
                    },
                    to,
                    frames,
                    &film,
                );
                crate::app::zoom::check(&job).map_err(|e| e.renamed("to", "w"))?;
                Ok((commands.zoom_lyapunov)(&job))
            }
        }
    })
    .await;
    match result {
        Ok(Ok(command)) => json(serde_json::json!({ "command": command })),
        Ok(Err(e)) => reply(e),
        Err(e) => reply(Error::Gpu(format!("the work failed: {e}"))),
    }
}

/// Counters since the start, and the queue now.
pub(super) async fn stats(AxumState(shared): AxumState<S>) -> Response {
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
