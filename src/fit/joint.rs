//! Where the middle joint lies when the upper marker is not on it (a sticker at the upper
//! bar's centre, a bob short of the joint). The lower marker keeps a fixed distance r2 from
//! the joint J = L u1, u1 the upper arm's direction from the pivot (which the upper marker
//! gives wherever it sits on the arm): |p2 - L u1|^2 = r2^2, that is
//! |p2|^2 = 2 L (p2 . u1) + (r2^2 - L^2), a straight line in (p2 . u1, |p2|^2) whose slope
//! is 2 L. Linear least squares over the track gives L with its error; the joint's positions
//! then stand in for the upper marker's, so the rest of the fit sees a marker on the joint.

use super::TrackedRow;

/// The joint placed along the upper arm: the upper marker's radius (m, median), the joint's
/// distance from the pivot and its standard error.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Joint {
    pub marker: f64,
    pub joint: f64,
    pub error: f64,
}

/// A joint this many standard errors from the upper marker, and further than
/// [`OFF_SHARE`] of its radius, is off it: the markers at the joint give |z| < 5 but for one
/// track in 1.7 million.
const OFF_Z: f64 = 5.0;

/// Closer than this share of the upper arm, the marker is taken to be on the joint: the
/// model's error from so small an offset lies under the tracking error of a film.
const OFF_SHARE: f64 = 0.02;

/// The joint's distance from the pivot, where `frames` (relative to `pivot`) say it lies
/// off the upper marker; None where the marker is on it or the motion cannot tell (the
/// lower arm must turn against the upper).
pub fn joint_off_marker(frames: &[TrackedRow], pivot: (f64, f64)) -> Option<Joint> {
    let mut radii = Vec::with_capacity(frames.len());
    let (mut sx, mut sy, mut sxx, mut sxy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut points = Vec::with_capacity(frames.len());
    for f in frames {
        let (dx1, dy1) = (f.x1 - pivot.0, f.y1 - pivot.1);
        let (dx2, dy2) = (f.x2 - pivot.0, f.y2 - pivot.1);
        let r1 = dx1.hypot(dy1);
        if !(r1 > 0.0 && dx2.is_finite() && dy2.is_finite()) {
            continue;
        }
        radii.push(r1);
        let x = (dx2 * dx1 + dy2 * dy1) / r1;
        let y = dx2 * dx2 + dy2 * dy2;
        points.push((x, y));
        (sx, sy, sxx, sxy, n) = (sx + x, sy + y, sxx + x * x, sxy + x * y, n + 1.0);
    }
    if n < 10.0 {
        return None;
    }
    radii.sort_by(f64::total_cmp);
    let marker = radii[radii.len() / 2];
    let var_x = sxx - sx * sx / n;
    if var_x <= 0.0 {
        return None;
    }
    let slope = (sxy - sx * sy / n) / var_x;
    let intercept = (sy - slope * sx) / n;
    let s2 = points
        .iter()
        .map(|(x, y)| (y - slope * x - intercept).powi(2))
        .sum::<f64>()
        / (n - 2.0);
    let joint = 0.5 * slope;
    let error = 0.5 * (s2 / var_x).sqrt();
    // The lower marker's radius from the joint must come out real.
    let r2_squared = intercept + joint * joint;
    let off = (joint - marker).abs();
    (r2_squared > 0.0 && joint > 0.0 && off > OFF_Z * error && off > OFF_SHARE * marker).then_some(
        Joint {
            marker,
            joint,
            error,
        },
    )
}

impl Joint {
    /// `frames` with the upper marker moved out along its arm to the joint.
    pub fn moved(&self, frames: &[TrackedRow], pivot: (f64, f64)) -> Vec<TrackedRow> {
        let k = self.joint / self.marker;
        frames
            .iter()
            .map(|f| TrackedRow {
                x1: pivot.0 + k * (f.x1 - pivot.0),
                y1: pivot.1 + k * (f.y1 - pivot.1),
                ..*f
            })
            .collect()
    }
}

/// Where the markers sit off the arms' axes by a fraction of a pixel, as the lower rod's
/// length shows it: the upper marker `along` and `across` the upper arm from the middle
/// joint (a sticker's centre beside the axle), and the lower marker seen `lower` off in the
/// picture (its colour's centroid leaning one way against the upper's). Each bends the
/// model's lower arm by as much as the tracking error, always the same way: the fit takes
/// it for motion (on IBM's films 0.3 px each, and the forecasts followed for half as long
/// as on a film made without them). In the frames' units, each with its standard error.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Offsets {
    pub along: f64,
    pub across: f64,
    pub lower: (f64, f64),
    pub errors: [f64; 4],
    /// Whether they are a calibration's (`forecast --params`) rather than the rows' own.
    pub from_calibration: bool,
}

/// The offsets' linear least squares: the lower rod's length r2 = |m2 - m1| moves by
/// -(along u1 + across n1 - lower) . u2 to first order (u1, n1 along and across the upper
/// arm, u2 along the lower), the square of an offset over the arm's length (1e-3 px) below
/// any tracker's error; the errors widened by the residuals' correlation from row to row.
/// Each offset is shrunk toward zero by its own error ([`shrunk`]). None where fewer than
/// [`OFFSET_ROWS`] rows, where the motion cannot tell them apart (the arms never turn
/// against each other), or where one comes out over [`OFF_SHARE`] of its arm: no small
/// offset, but a table's hand-placed points (the lab's 67 rows gave 12 and 18 mm at four of
/// their errors) or a marker far off the joint, which [`joint_off_marker`] places.
pub fn marker_offsets(frames: &[TrackedRow], pivot: (f64, f64)) -> Option<Offsets> {
    let mut normal = nalgebra::SMatrix::<f64, 5, 5>::zeros();
    let mut right = nalgebra::SVector::<f64, 5>::zeros();
    let mut rows = Vec::with_capacity(frames.len());
    for f in frames {
        // A row with a mass unseen (NaN) or an arm of no length says nothing.
        let Some((u1, n1, u2, r2)) = axes(f, pivot) else {
            continue;
        };
        let x = nalgebra::SVector::<f64, 5>::from([1.0, -dot(u1, u2), -dot(n1, u2), u2.0, u2.1]);
        if !(x.iter().all(|v| v.is_finite()) && r2.is_finite()) {
            continue;
        }
        normal += x * x.transpose();
        right += x * r2;
        rows.push((x, r2));
    }
    if rows.len() < OFFSET_ROWS {
        return None;
    }
    let inverse = normal.try_inverse()?;
    let c = inverse * right;
    let upper = frames
        .iter()
        .map(|f| (f.x1 - pivot.0).hypot(f.y1 - pivot.1))
        .filter(|r| r.is_finite())
        .fold(0.0, f64::max);
    if c[1].hypot(c[2]) > OFF_SHARE * upper || c[3].hypot(c[4]) > OFF_SHARE * c[0] {
        return None;
    }
    let residuals: Vec<f64> = rows.iter().map(|(x, r)| r - x.dot(&c)).collect();
    let s2 = residuals.iter().map(|e| e * e).sum::<f64>() / (rows.len() - 5) as f64;
    let (_, _, inflation) = super::correlation::long_run(&[residuals]);
    let error = |k: usize| (s2 * inflation * inverse[(k, k)]).sqrt();
    let errors = [error(1), error(2), error(3), error(4)];
    Some(Offsets {
        along: shrunk(c[1], errors[0]),
        across: shrunk(c[2], errors[1]),
        lower: (shrunk(c[3], errors[2]), shrunk(c[4], errors[3])),
        errors,
        from_calibration: false,
    })
}

/// The fewest rows that show the markers' small offsets: a film's second or more.
const OFFSET_ROWS: usize = 400;

/// An estimate applied as a correction, shrunk toward zero by its error: x (1 - (e/x)^2),
/// none where |x| <= e. Of the estimate itself (its error e) and none at all (its bias x),
/// the better correction is the one with the smaller square error; the shrunk one is better
/// than either (James and Stein's rule for one quantity).
pub fn shrunk(x: f64, error: f64) -> f64 {
    if x.abs() <= error {
        0.0
    } else {
        x * (1.0 - (error / x).powi(2))
    }
}

fn dot(a: (f64, f64), b: (f64, f64)) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

/// The upper arm's direction and its normal, the lower arm's direction and its length.
type Axes = ((f64, f64), (f64, f64), (f64, f64), f64);

/// A row's [`Axes`], none where an arm has no length.
fn axes(f: &TrackedRow, pivot: (f64, f64)) -> Option<Axes> {
    let (dx1, dy1) = (f.x1 - pivot.0, f.y1 - pivot.1);
    let r1 = dx1.hypot(dy1);
    let (dx2, dy2) = (f.x2 - f.x1, f.y2 - f.y1);
    let r2 = dx2.hypot(dy2);
    let u1 = (dx1 / r1, dy1 / r1);
    (r1 > 0.0 && r2 > 0.0).then_some((u1, (-u1.1, u1.0), (dx2 / r2, dy2 / r2), r2))
}

impl Offsets {
    /// `frames` with the upper marker moved onto the joint and the lower marker's lean taken
    /// out.
    pub fn moved(&self, frames: &[TrackedRow], pivot: (f64, f64)) -> Vec<TrackedRow> {
        frames
            .iter()
            .map(|f| match axes(f, pivot) {
                Some((u1, n1, _, _)) => TrackedRow {
                    x1: f.x1 - self.along * u1.0 - self.across * n1.0,
                    y1: f.y1 - self.along * u1.1 - self.across * n1.1,
                    x2: f.x2 - self.lower.0,
                    y2: f.y2 - self.lower.1,
                    ..*f
                },
                None => *f,
            })
            .collect()
    }

    /// Whether any offset survived its shrinking.
    pub fn any(&self) -> bool {
        self.along != 0.0 || self.across != 0.0 || self.lower != (0.0, 0.0)
    }

    /// The offsets in other units (pixels to metres: 1/ppm).
    pub fn scaled(&self, k: f64) -> Offsets {
        Offsets {
            along: self.along * k,
            across: self.across * k,
            lower: (self.lower.0 * k, self.lower.1 * k),
            errors: self.errors.map(|e| e * k),
            from_calibration: self.from_calibration,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Markers at 0.6 of a 0.1 m upper arm and 0.08 m down the lower one, turning: the joint
    /// is found at 0.1 m; with the marker on the joint, none is reported.
    #[test]
    fn the_joint_is_found_along_the_upper_arm() {
        let rows = |at: f64| -> Vec<TrackedRow> {
            (0..400)
                .map(|k| {
                    let t = k as f64 * 0.01;
                    let (a, b) = ((3.0 * t).sin(), 5.0 * t);
                    let (jx, jy) = (0.1 * a.sin(), -0.1 * a.cos());
                    TrackedRow {
                        t,
                        x1: at * jx,
                        y1: at * jy,
                        x2: jx + 0.08 * b.sin(),
                        y2: jy - 0.08 * b.cos(),
                    }
                })
                .collect()
        };
        let j = joint_off_marker(&rows(0.6), (0.0, 0.0)).expect("off the joint");
        assert!((j.joint - 0.1).abs() < 1e-9, "{j:?}");
        assert!((j.marker - 0.06).abs() < 1e-9, "{j:?}");
        assert!(joint_off_marker(&rows(1.0), (0.0, 0.0)).is_none());
    }

    /// Markers a fraction of a pixel off the axes (the upper 0.3 along and 0.16 across its
    /// arm from the joint, the lower seen 0.22 below where it is) on a turning pendulum with
    /// 0.1 px of noise: each offset is found within four of its errors, which are under
    /// 0.02 px; the moved frames put the lower marker at its rod's length from the joint.
    #[test]
    fn markers_off_the_axes_are_found_and_taken_out() {
        let (along, across, lower) = (0.3, 0.16, (0.0, -0.22));
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut frames: Vec<TrackedRow> = (0..4000)
            .map(|k| {
                let t = k as f64 / 400.0;
                let (a, b) = (2.0 * (3.0 * t).sin(), 5.0 * t);
                let (u1, n1) = ((a.sin(), -a.cos()), (a.cos(), a.sin()));
                let (jx, jy) = (120.0 * u1.0, 120.0 * u1.1);
                let mut e = || -> f64 {
                    let z: f64 = rand_distr::StandardNormal.sample(&mut rng);
                    0.1 * z
                };
                TrackedRow {
                    t,
                    x1: jx + along * u1.0 + across * n1.0 + e(),
                    y1: jy + along * u1.1 + across * n1.1 + e(),
                    x2: jx + 92.0 * b.sin() + lower.0 + e(),
                    y2: jy - 92.0 * b.cos() + lower.1 + e(),
                }
            })
            .collect();
        // A frame with the lower mass unseen is passed over, not the end of the fit.
        (frames[100].x2, frames[100].y2) = (f64::NAN, f64::NAN);
        let o = marker_offsets(&frames, (0.0, 0.0)).expect("offsets");
        let found = [o.along, o.across, o.lower.0, o.lower.1];
        for (k, truth) in [along, across, lower.0, lower.1].into_iter().enumerate() {
            // 1e-3 px: the first-order model's own error, an offset squared over the arm.
            assert!((found[k] - truth).abs() < 4.0 * o.errors[k] + 1e-3, "{o:?}");
            assert!(o.errors[k] < 0.02, "{o:?}");
        }
        let moved = o.moved(&frames, (0.0, 0.0));
        let spread = |f: &[TrackedRow]| {
            let r: Vec<f64> = f
                .iter()
                .map(|f| (f.x2 - f.x1).hypot(f.y2 - f.y1))
                .filter(|r| r.is_finite())
                .collect();
            let mean = r.iter().sum::<f64>() / r.len() as f64;
            (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt()
        };
        // The rod's length then varies by the noise alone (two ends of 0.1 px: 0.14 px).
        assert!(
            spread(&moved) < 0.16 && spread(&frames) > 0.2,
            "{} {}",
            spread(&moved),
            spread(&frames)
        );
    }
}
