//! Markers in one frame: bright blobs above the background's noise, each measured by its
//! light-weighted centroid (sub-pixel), its light (flux) and its second moments (a marker
//! smeared into a streak by the exposure is measured as a streak: its centroid is the mean
//! position over the exposure, its length and direction the motion during it).

/// What the markers look like.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Markers {
    /// Bright on a dark background (the lab's LEDs in a dark room): the frame's luma.
    Bright,
    /// Both of this colour on a lighter or other-coloured background: each pixel's colour
    /// along the marker's hue (its chroma projected on the marker's).
    Colour([u8; 3]),
    /// The upper marker of one colour, the lower of another (and a marker at the pivot of a
    /// third, where there is one): each found on its own colour's score, so that which
    /// mass a blob is follows from its colour as well as from the geometry.
    Colours {
        upper: [u8; 3],
        lower: [u8; 3],
        pivot: Option<[u8; 3]>,
    },
}

/// Colour names a marker may be given by, and the colour a sticker of that name shows a
/// camera in ordinary light (its hue is what matters: the score follows the hue).
pub const COLOUR_NAMES: [(&str, [u8; 3]); 9] = [
    ("red", [0xe0, 0x20, 0x20]),
    ("orange", [0xf0, 0x80, 0x20]),
    ("yellow", [0xe0, 0xd0, 0x20]),
    ("green", [0x20, 0xa0, 0x40]),
    ("cyan", [0x20, 0xc0, 0xd0]),
    ("blue", [0x20, 0x40, 0xe0]),
    ("purple", [0x80, 0x30, 0xc0]),
    ("magenta", [0xd0, 0x20, 0xd0]),
    ("pink", [0xff, 0x60, 0xa0]),
];

/// Which mass a blob may be: either (one look for both markers), or the one whose colour
/// it has; or the pivot's marker, by its own colour (a marker of one look at the pivot is
/// told by its place: [`super::pivot`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Either,
    Upper,
    Lower,
    Pivot,
}

impl Role {
    /// Every role, each at its own index (`role as usize`).
    pub const ALL: [Role; 4] = [Role::Either, Role::Upper, Role::Lower, Role::Pivot];
}

impl Markers {
    /// `bright`, or one colour, or two (the upper marker's first) and a third for a marker
    /// at the pivot, each as RRGGBB (`ff2020`, a leading `#` allowed) or a name (`red`,
    /// `green`...).
    pub fn parse(s: &str) -> Result<Markers, String> {
        if s == "bright" {
            return Ok(Markers::Bright);
        }
        let names = COLOUR_NAMES.map(|(n, _)| n).join(", ");
        let colour = |c: &str| -> Result<[u8; 3], String> {
            let c = c.trim();
            if let Some((_, rgb)) = COLOUR_NAMES.iter().find(|(n, _)| n.eq_ignore_ascii_case(c)) {
                return Ok(*rgb);
            }
            let hex = c.trim_start_matches('#');
            let byte = |k: usize| {
                hex.get(k..k + 2)
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
            };
            match (hex.len(), byte(0), byte(2), byte(4)) {
                (6, Some(r), Some(g), Some(b)) if r.max(g).max(b) - r.min(g).min(b) >= 40 => {
                    Ok([r, g, b])
                }
                (6, Some(_), Some(_), Some(_)) => Err(format!(
                    "{c} is grey or nearly: a marker's colour must differ from grey (its channels by 40 levels or more) for its hue to be found"
                )),
                _ => Err(format!(
                    "{c}: bright, or a colour as RRGGBB (e.g. ff2020) or a name ({names}); two colours as UPPER,LOWER, three as UPPER,LOWER,PIVOT"
                )),
            }
        };
        let given: Vec<&str> = s.split(',').collect();
        if given.len() > 3 {
            return Err(format!(
                "{s}: at most three colours, the upper marker's, the lower's and the pivot's (e.g. red,green,blue)"
            ));
        }
        let colours = given
            .iter()
            .map(|c| colour(c))
            .collect::<Result<Vec<_>, _>>()?;
        for i in 0..colours.len() {
            for j in i + 1..colours.len() {
                if hue_cosine(colours[i], colours[j]) > 0.5 {
                    return Err(format!(
                        "{} and {} are too alike in hue to tell the markers apart (their hues within 60 degrees): give colours further apart, or one colour for both masses",
                        given[i].trim(),
                        given[j].trim()
                    ));
                }
            }
        }
        Ok(match colours[..] {
            [one] => Markers::Colour(one),
            [upper, lower] => Markers::Colours {
                upper,
                lower,
                pivot: None,
            },
            [upper, lower, pivot] => Markers::Colours {
                upper,
                lower,
                pivot: Some(pivot),
            },
            _ => unreachable!("one to three colours"),
        })
    }

    /// The bytes a pixel of a decoded frame takes: 1 (luma) or 3 (RGB).
    pub fn channels(self) -> usize {
        match self {
            Markers::Bright => 1,
            Markers::Colour(_) | Markers::Colours { .. } => 3,
        }
    }

    /// The looks searched for, each with the role a blob of it takes.
    fn looks(self) -> Vec<(Option<[u8; 3]>, Role)> {
        match self {
            Markers::Bright => vec![(None, Role::Either)],
            Markers::Colour(c) => vec![(Some(c), Role::Either)],
            Markers::Colours {
                upper,
                lower,
                pivot,
            } => {
                let mut looks = vec![(Some(upper), Role::Upper), (Some(lower), Role::Lower)];
                looks.extend(pivot.map(|p| (Some(p), Role::Pivot)));
                looks
            }
        }
    }

    /// The blobs of one decoded frame (`width` wide) within `region`, each with its role.
    pub fn find(
        self,
        frame: &[u8],
        width: usize,
        region: Option<(usize, usize, usize, usize)>,
        scratch: &mut Scratch,
    ) -> Vec<Blob> {
        let mut out = Vec::new();
        for (colour, role) in self.looks() {
            let mut score = std::mem::take(&mut scratch.score);
            score_into(colour, frame, &mut score);
            out.extend(
                blobs(&score, width, region, scratch)
                    .into_iter()
                    .map(|b| Blob { role, ..b }),
            );
            scratch.score = score;
        }
        out
    }
}

/// How alike two colours' hues are: the cosine between their chroma vectors.
pub(super) fn hue_cosine(a: [u8; 3], b: [u8; 3]) -> f32 {
    let (a, b) = (chroma_direction(a), chroma_direction(b));
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A colour's chroma (its channels less their mean), as a unit vector.
pub(super) fn chroma_direction([r, g, b]: [u8; 3]) -> [f32; 3] {
    let grey = (r as f32 + g as f32 + b as f32) / 3.0;
    let dir = [r as f32 - grey, g as f32 - grey, b as f32 - grey];
    let norm = (dir.iter().map(|d| d * d).sum::<f32>()).sqrt().max(1.0);
    dir.map(|d| d / norm)
}

/// Luma as it is (no colour), or each RGB pixel's chroma along `colour`'s: grey, however
/// lit, scores nothing, and a sticker in shade scores in proportion to its light.
fn score_into(colour: Option<[u8; 3]>, frame: &[u8], out: &mut Vec<f32>) {
    out.clear();
    match colour {
        None => out.extend(frame.iter().map(|&v| v as f32)),
        Some(c) => {
            let dir = chroma_direction(c);
            out.extend(frame.chunks_exact(3).map(|p| {
                let grey = (p[0] as f32 + p[1] as f32 + p[2] as f32) / 3.0;
                let chroma = [p[0] as f32 - grey, p[1] as f32 - grey, p[2] as f32 - grey];
                (chroma[0] * dir[0] + chroma[1] * dir[1] + chroma[2] * dir[2]).max(0.0)
            }));
        }
    }
}

impl std::fmt::Display for Markers {
    /// As `--markers` takes it back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let hex = |[r, g, b]: [u8; 3]| format!("{r:02x}{g:02x}{b:02x}");
        match *self {
            Markers::Bright => write!(f, "bright"),
            Markers::Colour(c) => write!(f, "{}", hex(c)),
            Markers::Colours {
                upper,
                lower,
                pivot,
            } => {
                write!(f, "{},{}", hex(upper), hex(lower))?;
                match pivot {
                    Some(p) => write!(f, ",{}", hex(p)),
                    None => Ok(()),
                }
            }
        }
    }
}

/// A blob of light: centroid (px, x right, y down), its standard errors from the noise,
/// the light above the background, the pixels it covers and its spread along its long and
/// short axes (px, standard deviations) with the long axis's direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blob {
    pub x: f64,
    pub y: f64,
    pub sx: f64,
    pub sy: f64,
    pub flux: f64,
    pub area: u32,
    pub long: f64,
    pub short: f64,
    pub angle: f64,
    /// The centroid and light of the blob's core alone (its pixels above half its peak):
    /// where a dimmer blob (a reflection) runs into a marker, the core is the marker's.
    pub core: (f64, f64, f64),
    /// Which mass it may be (by its colour).
    pub role: Role,
}

impl Blob {
    /// A round blob at (x, y) of a marker's light, for the tests.
    #[cfg(test)]
    pub(crate) fn round(x: f64, y: f64, role: Role) -> Blob {
        Blob {
            x,
            y,
            sx: 0.05,
            sy: 0.05,
            flux: 100.0,
            area: 20,
            long: 1.0,
            short: 1.0,
            angle: 0.0,
            core: (x, y, 100.0),
            role,
        }
    }

    pub fn may_be_upper(&self) -> bool {
        matches!(self.role, Role::Either | Role::Upper)
    }

    pub fn may_be_lower(&self) -> bool {
        matches!(self.role, Role::Either | Role::Lower)
    }

    /// The streak's length (px): a segment of length L blurred by the marker's own profile
    /// spreads L^2 / 12 more along it than across.
    pub fn streak(&self) -> f64 {
        (12.0 * (self.long * self.long - self.short * self.short).max(0.0)).sqrt()
    }
}

/// The background's level and noise of a marker-ness image: the median and 1.4826 times
/// the median absolute deviation of every 29th pixel (markers cover too little to move
/// them).
pub fn background(score: &[f32]) -> (f32, f32) {
    let mut s: Vec<f32> = score.iter().step_by(29).copied().collect();
    if s.is_empty() {
        return (0.0, 1.0);
    }
    let mid = s.len() / 2;
    let level = *s.select_nth_unstable_by(mid, f32::total_cmp).1;
    let mut dev: Vec<f32> = s.iter().map(|v| (v - level).abs()).collect();
    let noise = *dev.select_nth_unstable_by(mid, f32::total_cmp).1 * 1.4826;
    // Quantised frames of a very clean camera: at least a level's rounding.
    (level, noise.max(0.5))
}

/// `score` averaged over 5 x 5 pixels (the edges over what lies inside), into `out`: a
/// marker's light stands out of the noise five times as far there, which finds a marker
/// smeared thin by a long exposure.
fn box5(score: &[f32], width: usize, rows: &mut Vec<f32>, out: &mut Vec<f32>) {
    let height = score.len() / width;
    // Rows first, by a running sum along each row; then columns, by a running sum of whole
    // rows (memory read in order both times).
    rows.clear();
    rows.resize(score.len(), 0.0);
    for y in 0..height {
        let (row, sums) = (
            &score[y * width..(y + 1) * width],
            &mut rows[y * width..(y + 1) * width],
        );
        let mut sum: f32 = row[..2.min(width)].iter().sum();
        for x in 0..width {
            if x + 2 < width {
                sum += row[x + 2];
            }
            if x >= 3 {
                sum -= row[x - 3];
            }
            let n = (x + 3).min(width) - x.saturating_sub(2);
            sums[x] = sum / n as f32;
        }
    }
    out.clear();
    out.resize(score.len(), 0.0);
    let mut sum = vec![0.0f32; width];
    for y in 0..2.min(height) {
        for (s, v) in sum.iter_mut().zip(&rows[y * width..(y + 1) * width]) {
            *s += v;
        }
    }
    for y in 0..height {
        if y + 2 < height {
            for (s, v) in sum.iter_mut().zip(&rows[(y + 2) * width..(y + 3) * width]) {
                *s += v;
            }
        }
        if y >= 3 {
            for (s, v) in sum.iter_mut().zip(&rows[(y - 3) * width..(y - 2) * width]) {
                *s -= v;
            }
        }
        let n = ((y + 3).min(height) - y.saturating_sub(2)) as f32;
        for (o, s) in out[y * width..(y + 1) * width].iter_mut().zip(&sum) {
            *o = s / n;
        }
    }
}

/// Scratch a frame's search reuses.
#[derive(Default)]
pub struct Scratch {
    score: Vec<f32>,
    visited: Vec<bool>,
    rows: Vec<f32>,
    smooth: Vec<f32>,
}

/// Finds the blobs of `score` (`width` wide) within `region` (x0, y0, x1, y1; None: all).
/// Where a blob is, is decided on the 5 x 5 average: seeds 6 of its noise deviations above
/// its background (and 4 levels), grown over what is 3 deviations above, 8-connected; what
/// it is, from `score` itself over those pixels.
pub fn blobs(
    score: &[f32],
    width: usize,
    region: Option<(usize, usize, usize, usize)>,
    scratch: &mut Scratch,
) -> Vec<Blob> {
    let height = score.len() / width;
    let (level, noise) = background(score);
    box5(score, width, &mut scratch.rows, &mut scratch.smooth);
    let smooth = &scratch.smooth;
    let (level_s, noise_s) = background(smooth);
    let seed = level_s + (6.0 * noise_s).max(4.0);
    let grow = level_s + 3.0 * noise_s;
    let visited = &mut scratch.visited;
    visited.clear();
    visited.resize(score.len(), false);
    let (x0, y0, x1, y1) = region.unwrap_or((0, 0, width, height));
    let (x1, y1) = (x1.min(width), y1.min(height));
    let mut out = Vec::new();
    let mut stack = Vec::new();
    let mut pixels: Vec<usize> = Vec::new();
    for y in y0..y1 {
        let row = &smooth[y * width..(y + 1) * width];
        for x in x0..x1 {
            if row[x] < seed || visited[y * width + x] {
                continue;
            }
            pixels.clear();
            stack.push(y * width + x);
            visited[y * width + x] = true;
            while let Some(k) = stack.pop() {
                pixels.push(k);
                let (px, py) = (k % width, k / width);
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (nx, ny) = (px as i64 + dx, py as i64 + dy);
                        if nx < x0 as i64 || ny < y0 as i64 || nx >= x1 as i64 || ny >= y1 as i64 {
                            continue;
                        }
                        let n = ny as usize * width + nx as usize;
                        if !visited[n] && smooth[n] >= grow {
                            visited[n] = true;
                            stack.push(n);
                        }
                    }
                }
                // A blob the size of a lamp's glare is not a marker: stop growing it.
                if pixels.len() > 20_000 {
                    stack.clear();
                }
            }
            if let Some(b) = measure(score, width, &pixels, level, noise) {
                out.push(b);
            }
        }
    }
    out
}

/// The blob of `pixels`: light-weighted moments over the light above `level`.
/// The weights are the light above the background, negative ones too: the noise over the
/// region's margins then averages out instead of pulling the centroid to the region's middle.
fn measure(score: &[f32], width: usize, pixels: &[usize], level: f32, noise: f32) -> Option<Blob> {
    let (mut f, mut fx, mut fy) = (0.0f64, 0.0f64, 0.0f64);
    for &k in pixels {
        let w = (score[k] - level) as f64;
        f += w;
        fx += w * (k % width) as f64;
        fy += w * (k / width) as f64;
    }
    if f.is_nan() || f <= 0.0 {
        return None;
    }
    let (x, y) = (fx / f, fy / f);
    let (mut cxx, mut cyy, mut cxy) = (0.0, 0.0, 0.0);
    for &k in pixels {
        let w = (score[k] - level) as f64;
        let (dx, dy) = ((k % width) as f64 - x, (k / width) as f64 - y);
        cxx += w * dx * dx;
        cyy += w * dy * dy;
        cxy += w * dx * dy;
    }
    // The centroid's standard error from independent noise on each pixel:
    // var(x̄) = noise^2 sum (x_i - x̄)^2 / F^2.
    let (mut sxx, mut syy) = (0.0, 0.0);
    for &k in pixels {
        let (dx, dy) = ((k % width) as f64 - x, (k / width) as f64 - y);
        sxx += dx * dx;
        syy += dy * dy;
    }
    let n = noise as f64;
    let (cxx, cyy, cxy) = (cxx / f, cyy / f, cxy / f);
    let peak = pixels
        .iter()
        .map(|&k| score[k] - level)
        .fold(0.0f32, f32::max);
    let (mut g, mut gx, mut gy) = (0.0f64, 0.0f64, 0.0f64);
    for &k in pixels {
        let w = score[k] - level;
        if w >= 0.5 * peak {
            g += w as f64;
            gx += w as f64 * (k % width) as f64;
            gy += w as f64 * (k / width) as f64;
        }
    }
    // The covariance's eigenvalues: the spreads along the blob's long and short axes.
    let mean = (cxx + cyy) / 2.0;
    let half = (((cxx - cyy) / 2.0).powi(2) + cxy * cxy).sqrt();
    if g <= 0.0 {
        return None;
    }
    Some(Blob {
        x,
        y,
        sx: n * sxx.sqrt() / f,
        sy: n * syy.sqrt() / f,
        flux: f,
        area: pixels.len() as u32,
        long: (mean + half).max(0.0).sqrt(),
        short: (mean - half).max(0.0).sqrt(),
        angle: 0.5 * (2.0 * cxy).atan2(cxx - cyy),
        core: (gx / g, gy / g, g),
        role: Role::Either,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian spot at a sub-pixel place, no noise: its centroid is found to 0.01 px;
    /// a uniform streak of 20 px is measured 20 px long along its direction.
    #[test]
    fn a_spot_and_a_streak_are_measured_where_they_are() {
        let (w, h) = (64usize, 48usize);
        let spot = |cx: f64, cy: f64, image: &mut [f32], a: f64| {
            for y in 0..h {
                for x in 0..w {
                    let r2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                    image[y * w + x] += (a * (-r2 / (2.0 * 2.5 * 2.5)).exp()) as f32;
                }
            }
        };
        let mut image = vec![10.0f32; w * h];
        spot(20.3, 17.8, &mut image, 200.0);
        let mut scratch = Scratch::default();
        let found = blobs(&image, w, None, &mut scratch);
        assert_eq!(found.len(), 1);
        assert!(
            (found[0].x - 20.3).abs() < 0.01 && (found[0].y - 17.8).abs() < 0.01,
            "{:?}",
            found[0]
        );
        let mut image = vec![10.0f32; w * h];
        for s in 0..200 {
            let u = s as f64 / 199.0;
            // 20 px along the direction (0.8, 0.6).
            spot(22.0 + 16.0 * u, 14.0 + 12.0 * u, &mut image, 4.0);
        }
        let found = blobs(&image, w, None, &mut scratch);
        assert_eq!(found.len(), 1);
        let b = found[0];
        assert!(
            (b.x - 30.0).abs() < 0.05 && (b.y - 20.0).abs() < 0.05,
            "{b:?}"
        );
        assert!((b.streak() - 20.0).abs() < 1.0, "{}", b.streak());
        assert!((b.angle - 0.6f64.atan2(0.8)).abs() < 0.02, "{}", b.angle);
    }

    /// A red marker on a light grey background (the documented option): its colour's score
    /// makes it a bright blob, found where it is; the grey background and a grey blob of the
    /// same contrast score nothing.
    #[test]
    fn a_coloured_marker_on_a_light_background_is_found() {
        let (w, h) = (64usize, 48usize);
        let mut rgb = vec![200u8; w * h * 3];
        let paint = |rgb: &mut [u8], cx: f64, cy: f64, colour: [f64; 3]| {
            for y in 0..h {
                for x in 0..w {
                    let r2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                    let a = (-r2 / (2.0 * 3.0 * 3.0)).exp();
                    for (c, v) in colour.iter().enumerate() {
                        let k = (y * w + x) * 3 + c;
                        rgb[k] = ((1.0 - a) * rgb[k] as f64 + a * v).round() as u8;
                    }
                }
            }
        };
        paint(&mut rgb, 40.4, 20.7, [230.0, 30.0, 30.0]);
        paint(&mut rgb, 15.0, 30.0, [60.0, 60.0, 60.0]);
        let found = Markers::parse("e01e1e")
            .unwrap()
            .find(&rgb, w, None, &mut Scratch::default());
        assert_eq!(found.len(), 1, "{found:?}");
        // Within 0.05 px: the picture is quantised to whole levels.
        assert!(
            (found[0].x - 40.4).abs() < 0.05 && (found[0].y - 20.7).abs() < 0.05,
            "{:?}",
            found[0]
        );
        assert_eq!(Markers::parse("red"), Markers::parse("E02020"));
        assert!(Markers::parse("#ff2020").is_ok() && Markers::parse("808080").is_err());
        assert_eq!(
            Markers::parse("red,green").unwrap().to_string(),
            "e02020,20a040"
        );
        assert_eq!(
            Markers::parse("red,green,blue").unwrap().to_string(),
            "e02020,20a040,2040e0"
        );
        // Two hues within 60 degrees, among two or three; four colours.
        for refused in ["red,orange", "red,green,orange", "red,green,blue,cyan"] {
            assert!(Markers::parse(refused).is_err(), "{refused}");
        }
    }
}
