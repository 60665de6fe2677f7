//! Tiles: a view over a tile's region computed as the map commands compute it, or read from
//! a store down to its own pixels; and the colour bar they are coloured with.

use super::answers::{cached, json, on_engine, png, remember, reply};
use super::{Kind, Params, Query, S, View, World, view};
use crate::engine::Engine;
use crate::engine::MapKernels;
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::render::MapPicture;
use crate::render::store::MapStore;
use crate::render::{self, PictureSpec};
use crate::spec::Grid;
use axum::body::Bytes;
use axum::extract::{Path, Query as AxumQuery, State as AxumState};
use axum::response::Response;
use std::sync::atomic::Ordering;

/// `spec`'s map (with `verdict`, its mask) as every door makes one: planned on the engine
/// ([`Engine::plan`]: its path, the checks that depend on it, the verdict's finer maps), then
/// computed; and the precision it ran in ("f32", "f64").
pub(super) fn planned<S: MapKernels>(
    engine: &Engine,
    spec: &S,
    verdict: bool,
    monitor: &Monitor,
) -> Result<(Field, Option<Vec<u8>>, &'static str)> {
    let plan = engine.plan(spec, verdict)?;
    let (field, mask) = engine.planned_map(&plan, monitor)?;
    Ok((field, mask, plan.info.path.precision().name()))
}

/// The tile (z, x, y), as the bare PNG `chaoscope flip` / `lyapunov` would make of it.
pub(super) async fn tile(
    AxumState(shared): AxumState<S>,
    Path((z, x, y)): Path<(String, String, String)>,
    AxumQuery(q): Params,
) -> Response {
    type Tile = (View, World, Grid, String, (u32, u64, u64));
    let parsed = (|| -> Result<Tile> {
        let int = |key: &'static str, s: &str| {
            s.parse::<u64>()
                .map_err(|_| Error::invalid(key, format!("{s:?} is not a tile index")))
        };
        let y = y.strip_suffix(".png").unwrap_or(&y);
        let (z, x, y) = (int("z", &z)?, int("x", &x)?, int("y", y)?);
        let mut q = Query::new(q)?;
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
        if shared.store.is_some() && view.region_given {
            return Err(Error::invalid(
                "x_min",
                "the store's map fixes the region its tiles cover",
            ));
        }
        let z = u32::try_from(z).unwrap_or(u32::MAX);
        let world = shared.world(&view);
        let grid = world.tile_grid(z, x, y, size)?;
        let key = format!("tile {z}/{x}/{y}/{size} {view:?}");
        Ok((view, world, grid, key, (z, x, y)))
    })();
    let (view, world, grid, key, (z, x, y)) = match parsed {
        Ok(p) => p,
        Err(e) => return reply(e),
    };
    if let Some(bytes) = cached(&shared, &key) {
        return png(bytes, "cached");
    }
    let store = shared.store.clone();
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
        Kind::FLIP | Kind::FLIP_KIND | Kind::Resolved => {
            let spec = view.flip_spec(grid);
            spec.validate()?;
            let verdict = view.unresolved || view.kind == Kind::Resolved;
            let (field, mask, precision) = planned(engine, &spec, verdict, monitor)?;
            let rgb = match (view.kind, mask) {
                (Kind::Resolved, Some(mask)) => mask_rgb(&mask),
                (_, mask) => {
                    let shown = mask.as_deref().filter(|_| view.unresolved);
                    spec.draw(&field, &picture, None, shown)?.picture.rgb
                }
            };
            Ok((rgb, precision))
        }
        Kind::Map(_) => {
            let spec = view.lyapunov_spec(grid);
            spec.validate()?;
            let (field, mask, precision) = planned(engine, &spec, view.unresolved, monitor)?;
            let rgb = spec
                .draw(&field, &picture, Some(view.range), mask.as_deref())?
                .picture
                .rgb;
            Ok((rgb, precision))
        }
    }
}

/// Where a tile lies on a stored map's region.
pub(super) struct StoredTile {
    world: World,
    z: u32,
    x: u64,
    y: u64,
    size: u32,
}

/// The colour of tile pixels beyond a stored map's edge (the page's background).
pub(super) const OUTSIDE_RGB: [u8; 3] = [42, 42, 48];

/// A tile at or above the store's own level: its pixels read from the store (the stored
/// pixel under each tile pixel's centre), coloured as `chaoscope render` colours them.
pub(super) fn stored_rgb(
    store: &MapStore,
    at: &StoredTile,
    view: &View,
    grid: Grid,
) -> Result<Vec<u8>> {
    let size = at.size as usize;
    let (width, height) = (at.world.plane.width as u64, at.world.plane.height as u64);
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
                        "the store has no verdict (make it with [[resolved=MAP.zarr]])",
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
        Kind::FLIP | Kind::FLIP_KIND => {
            view.flip_spec(grid)
                .draw(&field, &picture, None, shown)?
                .picture
                .rgb
        }
        Kind::Map(_) => {
            let spec = view.lyapunov_spec(grid);
            spec.draw(&field, &picture, Some(view.range), shown)?
                .picture
                .rgb
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

/// The colour bar of a view, from the tables the tiles are coloured with: colours from left
/// to right (early to late flips; regular to chaotic exponents), ticks as (fraction, label),
/// and the colours of never, NaN and unresolved pixels.
pub(super) async fn legend(AxumState(shared): AxumState<S>, AxumQuery(q): Params) -> Response {
    let view = match shared.view_only(q) {
        Ok(v) => v,
        Err(e) => return reply(e),
    };
    let (colors, ticks, label) = match view.kind {
        Kind::FLIP_KIND => {
            let (colors, ticks) = render::flip_kind_bar();
            (colors, ticks, "first flip".to_string())
        }
        Kind::FLIP | Kind::Resolved => {
            let colors = render::FlipColors {
                t_lo: render::FlipColors::t_lo(&view.params),
                t_max: view.stepping.t_max,
                colormap: view.colormap.unwrap_or(render::Colormap::Inferno),
            };
            // The bar runs late to early; the page reads left to right from early.
            let (mut table, ticks) = colors.bar();
            table.reverse();
            let ticks = ticks.into_iter().map(|(f, l)| (1.0 - f, l)).collect();
            (table, ticks, "flip time (s)".to_string())
        }
        Kind::Map(_) => render::lyapunov_bar(
            &view.lyapunov_spec(Grid::square(1)),
            view.range,
            view.colormap.unwrap_or(render::Colormap::Magma),
        ),
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
