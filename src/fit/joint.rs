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
}
