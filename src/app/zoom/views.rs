//! The views a zoom passes through and each frame's grid between them.

use crate::error::{Error, Result};
use crate::spec::{Grid, Range};

/// Where a zoom goes: a view of the plane by its centre on the map's axes and its width
/// along x (its height keeps the first view's proportions). (The explorer's `View` is what
/// its page shows.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    pub x: f64,
    pub y: f64,
    pub width: f64,
}

impl Target {
    /// The view a grid spans.
    pub fn of(grid: &Grid) -> Target {
        Target {
            x: grid.x.range.mid(),
            y: grid.y.range.mid(),
            width: grid.x.range.max - grid.x.range.min,
        }
    }
}

/// The grids of the `frames` frames from `start`'s view through `to`: widths geometric
/// between views, the centre moving so that one point stays in place on the screen (the
/// point a zoom closes in on); frames shared between the legs by how far each goes (its
/// zoom in e-folds, its pan in screens). Frame 0 is `start` itself.
pub fn grids(start: &Grid, to: &[Target], frames: u32) -> Result<Vec<Grid>> {
    if !(2..=100_000).contains(&frames) {
        return Err(Error::invalid(
            "frames",
            format!("{frames} must be between 2 and 100000"),
        ));
    }
    if to.is_empty() {
        return Err(Error::invalid(
            "to",
            "a zoom needs a view to go to: X,Y,WIDTH",
        ));
    }
    for v in to {
        if !(v.x.is_finite() && v.y.is_finite() && v.width.is_finite() && v.width > 0.0) {
            return Err(Error::invalid(
                "to",
                format!("{},{},{}: X,Y,WIDTH finite, WIDTH > 0", v.x, v.y, v.width),
            ));
        }
    }
    let first = Target::of(start);
    let aspect = (start.y.range.max - start.y.range.min) / first.width;
    let views: Vec<Target> = std::iter::once(first).chain(to.iter().copied()).collect();
    let legs: Vec<f64> = views
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let narrow = a.width.min(b.width);
            let pan = ((b.x - a.x) / narrow).hypot((b.y - a.y) / (narrow * aspect));
            (b.width / a.width).ln().abs() + pan
        })
        .collect();
    let total: f64 = legs.iter().sum();
    if total == 0.0 {
        return Err(Error::invalid(
            "to",
            "is the view the film starts from: give a view to zoom to",
        ));
    }
    let grid_of = |v: Target| grid_of_view(start, v);
    let last = frames - 1;
    Ok((0..frames)
        .map(|k| {
            if k == 0 {
                return *start;
            }
            if k == last {
                return grid_of(*views.last().expect("a view to go to"));
            }
            let mut along = total * k as f64 / last as f64;
            let mut leg = 0;
            while leg + 1 < legs.len() && along > legs[leg] {
                along -= legs[leg];
                leg += 1;
            }
            let (a, b) = (views[leg], views[leg + 1]);
            let u = (along / legs[leg]).clamp(0.0, 1.0);
            let width = a.width * (b.width / a.width).powf(u);
            // The share of the leg's centre travel: the one that keeps the point of the
            // screen the zoom closes in on fixed; a pan (equal widths) moves evenly.
            let moved = if (a.width - b.width).abs() > 1e-12 * a.width {
                (a.width - width) / (a.width - b.width)
            } else {
                u
            };
            grid_of(Target {
                x: a.x + (b.x - a.x) * moved,
                y: a.y + (b.y - a.y) * moved,
                width,
            })
        })
        .collect())
}

/// The grid of view `v` on `start`'s plane and pixels, its height in `start`'s proportions.
pub(super) fn grid_of_view(start: &Grid, v: Target) -> Grid {
    let aspect = (start.y.range.max - start.y.range.min) / Target::of(start).width;
    let h = v.width * aspect;
    let mut g = *start;
    g.x.range = Range {
        min: v.x - 0.5 * v.width,
        max: v.x + 0.5 * v.width,
    };
    g.y.range = Range {
        min: v.y - 0.5 * h,
        max: v.y + 0.5 * h,
    };
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane() -> Grid {
        use std::f64::consts::PI;
        Grid::angles(
            64,
            36,
            Range { min: -PI, max: PI },
            Range {
                min: -PI * 36.0 / 64.0,
                max: PI * 36.0 / 64.0,
            },
            0.0,
            0.0,
        )
    }

    /// Widths fall by the same factor each frame, and the point zoomed into keeps its place
    /// on the screen (its offset from the centre in widths shrinks with the width).
    #[test]
    fn a_zoom_is_geometric_about_a_fixed_point() {
        let start = plane();
        let end = Target {
            x: 1.0,
            y: -0.5,
            width: 1e-4,
        };
        let g = grids(&start, &[end], 61).unwrap();
        let w: Vec<f64> = g.iter().map(|g| Target::of(g).width).collect();
        let ratio = (w[60] / w[0]).powf(1.0 / 60.0);
        for k in 1..61 {
            // Each width the last times the ratio, to round-off of a few ulp per power.
            assert!((w[k] / w[k - 1] / ratio - 1.0).abs() < 1e-9, "frame {k}");
        }
        // The fixed point P: where the line from the first centre through the last meets
        // scale 0 (P = c0 + (c1 - c0) w0 / (w0 - w1)); its screen place (P - c) / w is the
        // same in every frame.
        let v0 = Target::of(&g[0]);
        let p = v0.x + (end.x - v0.x) * w[0] / (w[0] - w[60]);
        let place0 = (p - v0.x) / w[0];
        for gk in &g {
            let v = Target::of(gk);
            assert!(((p - v.x) / v.width - place0).abs() < 1e-6);
        }
        assert_eq!(g[0], start);
        assert_eq!(Target::of(&g[60]).x, end.x);
    }

    /// Legs get frames by how far they go: a leg of 4 e-folds twice a leg of 2.
    #[test]
    fn keyframes_share_the_frames_by_their_zoom() {
        let start = plane();
        let w0 = Target::of(&start).width;
        let via = Target {
            x: 0.0,
            y: 0.0,
            width: w0 * (-4.0f64).exp(),
        };
        let end = Target {
            width: via.width * (-2.0f64).exp(),
            ..via
        };
        let g = grids(&start, &[via, end], 31).unwrap();
        // 6 e-folds over 30 steps: frame 20 is the middle view.
        assert!((Target::of(&g[20]).width / via.width - 1.0).abs() < 1e-9);
    }

    #[test]
    fn bad_views_name_their_flag() {
        let start = plane();
        let v = Target {
            x: 0.0,
            y: 0.0,
            width: 0.0,
        };
        assert!(matches!(
            grids(&start, &[v], 10),
            Err(Error::InvalidSpec { field: "to", .. })
        ));
        assert!(matches!(
            grids(&start, &[Target::of(&start)], 10),
            Err(Error::InvalidSpec { field: "to", .. })
        ));
        assert!(matches!(
            grids(&start, &[Target { width: 1.0, ..v }], 1),
            Err(Error::InvalidSpec {
                field: "frames",
                ..
            })
        ));
    }
}
