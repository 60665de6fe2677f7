//! What the map's tiles cover: a region of a plane (any two axes, the rest fixed), as tiles of
//! Leaflet's zoom levels.

use super::view::MAX_ZOOM;
use crate::error::{Error, Result};
use crate::spec::{Axis, Grid, Range, Sampling};

/// A region of a plane that is `plane.width` x `plane.height` pixels at zoom level `native`
/// (tile pixels there are the region's pixels). Level 0's pixel units are Leaflet's
/// coordinates: the region spans `width / 2^native` of them across.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct World {
    pub plane: Grid,
    pub native: u32,
}

impl World {
    /// The whole turn [-pi, pi]^2 of starts from rest, as tile (0, 0, 0), computed at every
    /// level.
    pub fn turn() -> World {
        World::of_plane(&Grid::angles(
            256,
            256,
            Range::FULL_TURN,
            Range::FULL_TURN,
            0.0,
            0.0,
        ))
    }

    /// A plane's region (its size ignored) as tile (0, 0, 0), computed at every level.
    pub fn of_plane(plane: &Grid) -> World {
        World {
            plane: Grid {
                width: 256,
                height: 256,
                sampling: Sampling::Centres,
                ..*plane
            },
            native: 0,
        }
    }

    /// A stored map's grid: its own pixels at the first level where 256-pixel tiles hold
    /// them one to one.
    pub fn of_grid(grid: &Grid) -> World {
        let side = grid.width.max(grid.height).max(1) as f64;
        World {
            plane: *grid,
            native: (side / 256.0).log2().ceil().max(0.0) as u32,
        }
    }

    /// The region's size in level-0 pixel units (across, down).
    pub fn units(&self) -> (f64, f64) {
        let scale = (1u64 << self.native) as f64;
        (
            self.plane.width as f64 / scale,
            self.plane.height as f64 / scale,
        )
    }

    /// The axes' units per level-0 unit (x, y).
    pub fn per_unit(&self) -> (f64, f64) {
        let (w, h) = self.units();
        let span = |a: &Axis| a.range.max - a.range.min;
        (span(&self.plane.x) / w, span(&self.plane.y) / h)
    }

    /// Checks tile (z, x, y) lies on the region.
    pub fn check_tile(&self, z: u32, x: u64, y: u64) -> Result<()> {
        if z > MAX_ZOOM {
            return Err(Error::invalid(
                "z",
                format!("{z} must be at most {MAX_ZOOM}"),
            ));
        }
        let (w, h) = self.units();
        let tiles = |units: f64| (units * (1u64 << z) as f64 / 256.0).ceil() as u64;
        for (key, v, n) in [("x", x, tiles(w)), ("y", y, tiles(h))] {
            if v >= n {
                return Err(Error::invalid(
                    key,
                    format!("{v} lies outside level {z}'s tiles 0..{n}"),
                ));
            }
        }
        Ok(())
    }

    /// The grid of tile (z, x, y) with `size` pixels a side; y counts down from the top
    /// (the y axis' maximum).
    pub fn tile_grid(&self, z: u32, x: u64, y: u64, size: u32) -> Result<Grid> {
        self.check_tile(z, x, y)?;
        let span = 256.0 / (1u64 << z) as f64;
        let (kx, ky) = self.per_unit();
        // span * k is exact (a power of two times k), so the whole turn's tiles get
        // -pi + x * 2 pi / 2^z, the same numbers at every level.
        let (step_x, step_y) = (span * kx, span * ky);
        let (ax, ay) = (self.plane.x, self.plane.y);
        Ok(Grid {
            width: size,
            height: size,
            x: Axis::new(
                ax.var,
                ax.range.min + x as f64 * step_x,
                ax.range.min + (x + 1) as f64 * step_x,
            ),
            y: Axis::new(
                ay.var,
                ay.range.max - (y + 1) as f64 * step_y,
                ay.range.max - y as f64 * step_y,
            ),
            fixed: self.plane.fixed,
            sampling: Sampling::Centres,
        })
    }

    /// The region's pixel under pixel `k` of `size` along tile `t` of level `z` (<= native),
    /// sampled at the tile pixel's centre: column (or row) of the stored map.
    pub fn stored_pixel(&self, z: u32, t: u64, k: u32, size: u32) -> u64 {
        let scale = (1u64 << (self.native - z)) as f64;
        let unit = (t * 256) as f64 + (k as f64 + 0.5) * 256.0 / size as f64;
        (unit * scale).floor() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::Var;
    use std::f64::consts::PI;

    #[test]
    fn tiles_cover_the_turn_without_gaps() {
        let turn = World::turn();
        let a = turn.tile_grid(3, 2, 5, 256).unwrap();
        let b = turn.tile_grid(3, 3, 5, 256).unwrap();
        assert_eq!(a.x.range.max, b.x.range.min);
        assert_eq!(a.x.range.min, -PI + 2.0 * (2.0 * PI / 8.0));
        let top = turn.tile_grid(0, 0, 0, 256).unwrap();
        assert_eq!(
            (top.x.range, top.y.range),
            (Range::FULL_TURN, Range::FULL_TURN)
        );
        assert!(turn.tile_grid(3, 8, 0, 256).is_err());
        assert!(turn.tile_grid(MAX_ZOOM + 1, 0, 0, 256).is_err());
    }

    #[test]
    fn a_planes_tiles_keep_its_axes_and_fixed_start() {
        let plane = Grid {
            x: Axis::new(Var::MassRatio, 0.5, 2.5),
            y: Axis::new(Var::Omega1, -4.0, 4.0),
            ..Grid::angles(1, 1, Range::FULL_TURN, Range::FULL_TURN, 0.3, 0.0)
        };
        let world = World::of_plane(&plane);
        let g = world.tile_grid(1, 1, 0, 64).unwrap();
        assert_eq!((g.x.var, g.y.var), (Var::MassRatio, Var::Omega1));
        assert_eq!((g.x.range.min, g.x.range.max), (1.5, 2.5));
        assert_eq!((g.y.range.min, g.y.range.max), (0.0, 4.0));
        assert_eq!(g.fixed, plane.fixed);
        assert_eq!(g.width, 64);
    }

    #[test]
    fn a_stored_maps_tiles_hold_its_pixels_at_the_native_level() {
        let grid = Grid {
            width: 1000,
            height: 600,
            ..Grid::square(1)
        };
        let world = World::of_grid(&grid);
        assert_eq!(world.native, 2);
        // Level 2: tile pixel k of tile t is stored pixel 256 t + k; level 0 every 4th.
        assert_eq!(world.stored_pixel(2, 3, 7, 256), 3 * 256 + 7);
        assert_eq!(world.stored_pixel(0, 0, 10, 256), 42);
        assert!(world.check_tile(2, 3, 2).is_ok());
        assert!(
            world.check_tile(2, 3, 3).is_err(),
            "600 rows are 3 tiles down"
        );
        // The native level's tile grid has the stored map's pixel centres.
        let g = world.tile_grid(2, 1, 0, 256).unwrap();
        assert!((g.x_at(0) - grid.x_at(256)).abs() < 1e-12);
        assert!((g.y_at(5) - grid.y_at(5)).abs() < 1e-12);
    }
}
