//! Test films with a known truth: the two markers rendered from the model's own trajectory,
//! as the lab's camera saw its LEDs (bright on dark, 30 frames a second), with the exposure's
//! blur, sensor noise, a static lamp, a moving reflection and a table edge that hides the
//! lower mass, so that the tracker can be measured against where the markers really were.

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::model::{Params, State};

/// What the camera sees and how.
#[derive(Clone, Debug)]
pub struct Scene {
    pub width: u32,
    pub height: u32,
    /// Frames a second.
    pub fps: f64,
    /// Exposure of each frame (s), centred on the frame's time.
    pub shutter: f64,
    /// The pivot's place in the picture (px, x right, y down).
    pub pivot: (f64, f64),
    pub pixels_per_metre: f64,
    /// A marker's brightness profile: a Gaussian of this width (px).
    pub marker_sigma: f64,
    /// A still marker's peak above the background (levels of 255).
    pub marker_peak: f64,
    /// The dark background's level and the sensor noise's standard deviation (levels).
    pub background: f64,
    pub noise: f64,
    /// A static lamp (px), as bright and as large as a marker.
    pub lamp: Option<(f64, f64)>,
    /// A reflection of the lower marker in a pane at this column (px), at 40 % brightness:
    /// marker-sized and moving, but off the pendulum's geometry.
    pub reflection: Option<f64>,
    /// A second reflection of the whole pendulum (a glossy board, a window's other pane):
    /// both markers again, shifted by this offset (px) at this share of their brightness.
    pub ghost: Option<((f64, f64), f64)>,
    /// The table's top edge (px row): below it the table hides what is behind it.
    pub table: Option<f64>,
    /// The camera's roll (rad): the picture shows the world turned by this much
    /// counter-clockwise about the pivot, so that the picture's up is not the world's.
    pub roll: f64,
    /// Coloured stickers on a lit, textured grey board instead of lights in the dark: the
    /// upper and the lower marker's colours.
    pub stickers: Option<[[u8; 3]; 2]>,
    /// Seconds the pendulum hangs still before its release (the release at `rest`, from the
    /// film's start).
    pub rest: f64,
    /// Seconds after the rest in which a hand lifts the pendulum to its release (its angles
    /// eased from hanging to the start's over three quarters of it, then held still), the
    /// release at `rest + lift`.
    pub lift: f64,
    /// A marker on the axle: an LED like the masses' in the dark, or with stickers a sticker
    /// of this colour.
    pub pivot_marker: Option<[u8; 3]>,
    /// How far (px) the whole pendulum, its pivot's marker with it, wanders in the picture
    /// (a creeping tripod, a flexing stand): a slow drift of this amplitude in x and y.
    pub wander: f64,
    /// A hand (an arm from the picture's right edge) that comes in during the rest, holds
    /// the lower mass through the lift beside its marker, and is pulled away at the
    /// release: skin-coloured before the board, faintly lit in the dark.
    pub hand: bool,
    pub seed: u64,
}

impl Scene {
    /// The lab's camera on a 1280 x 720 (or any) frame: LEDs of 2.5 px, the pivot a fifth
    /// down the middle, the whole pendulum's reach within the frame.
    pub fn lab(width: u32, height: u32, reach: f64) -> Scene {
        Scene {
            width,
            height,
            fps: 30.0,
            shutter: 1.0 / 2000.0,
            pivot: (width as f64 / 2.0, height as f64 * 0.45),
            pixels_per_metre: 0.5 * width.min(height) as f64 / reach,
            marker_sigma: 2.5,
            marker_peak: 200.0,
            background: 12.0,
            noise: 2.0,
            lamp: None,
            reflection: None,
            ghost: None,
            table: None,
            roll: 0.0,
            stickers: None,
            rest: 0.0,
            lift: 0.0,
            pivot_marker: None,
            wander: 0.0,
            hand: false,
            seed: 1,
        }
    }

    /// Metres (origin at the pivot, y up) to pixels (x right, y down), through the camera's
    /// roll.
    pub fn to_pixels(&self, x: f64, y: f64) -> (f64, f64) {
        let (s, c) = self.roll.sin_cos();
        let (x, y) = (c * x - s * y, s * x + c * y);
        (
            self.pivot.0 + x * self.pixels_per_metre,
            self.pivot.1 - y * self.pixels_per_metre,
        )
    }

    /// The picture's shift at time `t` (px): the pendulum's [`Scene::wander`].
    pub fn shift(&self, t: f64) -> (f64, f64) {
        let tau = std::f64::consts::TAU;
        (
            self.wander * (tau * 0.37 * t + 0.3).sin(),
            self.wander * (tau * 0.23 * t).cos(),
        )
    }

    /// The hand's palm's centre (px) and radius at time `t`, given where the lower marker
    /// is: in from the right edge over the half second before the lift, holding the mass
    /// until the release, then pulled away to the right at two picture widths a second.
    fn hand_at(&self, t: f64, lower: (f64, f64), radius: f64) -> Option<(f64, f64)> {
        let holding = (lower.0 + radius + 2.0 * self.marker_sigma, lower.1);
        let outside = self.width as f64 + radius;
        let release = self.rest + self.lift;
        let x = if t < self.rest - 0.5 {
            return None;
        } else if t < self.rest {
            let u = (self.rest - t) / 0.5;
            holding.0 + u * (outside - holding.0)
        } else if t <= release {
            holding.0
        } else {
            holding.0 + 2.0 * self.width as f64 * (t - release)
        };
        (x < outside).then_some((x, holding.1))
    }
}

/// How much of pixel (`x`, `y`) a hand with its palm at `palm` (radius `r`) and its arm to
/// the picture's right covers: a capsule with an edge a pixel wide.
fn hand_cover(x: f64, y: f64, palm: (f64, f64), r: f64) -> f32 {
    // Right of the palm's centre the arm's straight edges; left of it the palm's round end.
    let d = if x > palm.0 {
        (y - palm.1).abs()
    } else {
        (x - palm.0).hypot(y - palm.1)
    };
    (r + 0.5 - d).clamp(0.0, 1.0) as f32
}

/// Where the markers really were in one frame: the mean position over its exposure (px),
/// and whether each was in view (wholly above the table's edge, `Some(true)`), hidden
/// (wholly below, `Some(false)`) or partly covered (`None`).
#[derive(Clone, Copy, Debug)]
pub struct TruthRow {
    pub t: f64,
    /// How far the picture had wandered ([`Scene::wander`], px): the positions below are
    /// the pendulum's own, from its pivot where the scene puts it ([`film`]'s: where the
    /// pivot stands on the film's median frame).
    pub shift: (f64, f64),
    pub m1: (f64, f64),
    pub m2: (f64, f64),
    pub seen1: Option<bool>,
    pub seen2: Option<bool>,
    /// The markers' mean positions (m, origin at the pivot, y up).
    pub metres: [f64; 4],
}

/// Renders gray frames of the pendulum `params` released from `start` (the first frame at
/// t = 0), one at a time, with the truth of each.
pub struct Renderer {
    scene: Scene,
    samples: usize,
    positions: Vec<crate::model::Positions>,
    rng: rand_pcg::Pcg64,
    noise: Vec<f32>,
    light: Vec<f32>,
    /// With stickers: each marker's cover of each pixel (0 to 1: the upper, the lower, the
    /// pivot's), and the board's light.
    cover: [Vec<f32>; 3],
    board: Vec<f32>,
    /// The hand's cover of each pixel (0 to 1).
    hand: Vec<f32>,
}

impl Renderer {
    pub fn new(scene: &Scene, params: &Params, start: State, frames: usize) -> Renderer {
        let (w, h) = (scene.width as usize, scene.height as usize);
        // Sub-exposure samples: neighbouring ones 0.2 px apart at the pendulum's fastest
        // (the lower bob at most (l1 + l2) * 20 rad/s).
        let fastest = (params.l1 + params.l2) * 20.0 * scene.pixels_per_metre;
        let samples = ((fastest * scene.shutter / 0.2).ceil() as usize).clamp(1, 400);
        let dt = 1e-3_f64.min(1.0 / scene.fps / 4.0);
        let times: Vec<f64> = (0..frames)
            .flat_map(|f| {
                let t = f as f64 / scene.fps;
                (0..samples).map(move |s| {
                    t - scene.shutter / 2.0 + scene.shutter * (s as f64 + 0.5) / samples as f64
                })
            })
            .map(|t| t.max(0.0))
            .collect();
        let t_end = (frames as f64 + 1.0) / scene.fps;
        let steps = (t_end / dt).ceil() as u32 + 1;
        // Hanging still until `rest`, lifted by hand until the release at `rest + lift`,
        // then swinging from `start`.
        let release = scene.rest + scene.lift;
        let swing: Vec<f64> = times.iter().map(|t| (t - release).max(0.0)).collect();
        let mut positions = crate::cpu::positions(params, start, dt, steps, &swing);
        for (p, t) in positions.iter_mut().zip(&times) {
            if *t < release {
                // Smoothstep from hanging (0) to the start's angles (1), then held.
                let u = ((t - scene.rest) / (0.75 * scene.lift).max(1e-9)).clamp(0.0, 1.0);
                let ease = u * u * (3.0 - 2.0 * u);
                *p = params.positions(&State::at_rest(ease * start.theta1, ease * start.theta2));
            }
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(scene.seed);
        // Sensor noise from a table of deviates read at a random offset each frame: as
        // random as the tests need, at a fraction of a normal deviate's cost per pixel.
        let normal = Normal::new(0.0, scene.noise).expect("finite");
        let noise: Vec<f32> = (0..(1 << 20) + w * h)
            .map(|_| normal.sample(&mut rng) as f32)
            .collect();
        // The board: lit from the left (a 0.75 to 1.15 gradient across the picture) with a
        // fixed texture of +-5 % in 4 px patches, under slightly warm light.
        let board = match scene.stickers {
            None => Vec::new(),
            Some(_) => {
                let patches = w.div_ceil(4) * h.div_ceil(4);
                let texture: Vec<f32> = (0..patches)
                    .map(|_| rng.random_range(-0.05f32..0.05))
                    .collect();
                (0..w * h)
                    .map(|k| {
                        let (x, y) = (k % w, k / w);
                        let gradient = 0.75 + 0.4 * x as f32 / w as f32;
                        gradient * (1.0 + texture[(y / 4) * w.div_ceil(4) + x / 4])
                    })
                    .collect()
            }
        };
        Renderer {
            scene: scene.clone(),
            samples,
            positions,
            rng,
            noise,
            light: vec![0.0; w * h],
            cover: match scene.stickers {
                None => [Vec::new(), Vec::new(), Vec::new()],
                Some(_) => [vec![0.0; w * h], vec![0.0; w * h], vec![0.0; w * h]],
            },
            board,
            hand: vec![0.0; if scene.hand { w * h } else { 0 }],
        }
    }

    /// Frame `f` as RGB (frames in order: the noise's stream follows them) and its truth.
    pub fn frame(&mut self, f: usize) -> (Vec<u8>, TruthRow) {
        let scene = &self.scene;
        let (w, h) = (scene.width as usize, scene.height as usize);
        let samples = self.samples;
        let sigma = scene.marker_sigma;
        let reach = (4.0 * sigma).ceil() as i64;
        let splat = |light: &mut [f32], (cx, cy): (f64, f64), amplitude: f64| {
            let (x0, y0) = (cx.round() as i64, cy.round() as i64);
            for y in (y0 - reach).max(0)..=(y0 + reach).min(h as i64 - 1) {
                for x in (x0 - reach).max(0)..=(x0 + reach).min(w as i64 - 1) {
                    let r2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                    light[y as usize * w + x as usize] +=
                        (amplitude * (-r2 / (2.0 * sigma * sigma)).exp()) as f32;
                }
            }
        };
        let light = &mut self.light;
        light.iter_mut().for_each(|v| *v = scene.background as f32);
        for c in &mut self.cover {
            c.iter_mut().for_each(|v| *v = 0.0);
        }
        let mut mean = [0.0f64; 4];
        let mut mean_m = [0.0f64; 4];
        // Each marker's highest and lowest row over the exposure.
        let mut rows = [(f64::INFINITY, f64::NEG_INFINITY); 2];
        let t = f as f64 / scene.fps;
        let shift = scene.shift(t);
        let moved = |p: (f64, f64)| (p.0 + shift.0, p.1 + shift.1);
        for s in 0..samples {
            let q = self.positions[f * samples + s];
            let (p1, p2) = (scene.to_pixels(q.x1, q.y1), scene.to_pixels(q.x2, q.y2));
            // The truth is the pendulum's own (from its pivot); the picture wanders.
            let (m1, m2) = (p1, p2);
            let (p1, p2) = (moved(p1), moved(p2));
            let a = scene.marker_peak / samples as f64;
            let shifted = |p: (f64, f64), (d, _): ((f64, f64), f64)| (p.0 + d.0, p.1 + d.1);
            if scene.stickers.is_some() {
                // A sticker covers its middle wholly and fades out over its edge.
                let a = 1.0 / samples as f64;
                splat(&mut self.cover[0], p1, a);
                splat(&mut self.cover[1], p2, a);
                if let Some(ghost) = scene.ghost {
                    splat(&mut self.cover[0], shifted(p1, ghost), ghost.1 * a);
                    splat(&mut self.cover[1], shifted(p2, ghost), ghost.1 * a);
                }
            } else {
                splat(light, p1, a);
                splat(light, p2, a);
                if let Some(ghost) = scene.ghost {
                    splat(light, shifted(p1, ghost), ghost.1 * a);
                    splat(light, shifted(p2, ghost), ghost.1 * a);
                }
            }
            if let Some(pane) = scene.reflection {
                splat(light, (2.0 * pane - p2.0, p2.1), 0.4 * a);
            }
            for (r, y) in rows.iter_mut().zip([p1.1, p2.1]) {
                *r = (r.0.min(y), r.1.max(y));
            }
            for (k, v) in [m1.0, m1.1, m2.0, m2.1].into_iter().enumerate() {
                mean[k] += v / samples as f64;
            }
            for (k, v) in [q.x1, q.y1, q.x2, q.y2].into_iter().enumerate() {
                mean_m[k] += v / samples as f64;
            }
        }
        if let Some(lamp) = scene.lamp {
            splat(light, lamp, scene.marker_peak);
        }
        if scene.pivot_marker.is_some() {
            match scene.stickers {
                Some(_) => splat(&mut self.cover[2], moved(scene.pivot), 1.0),
                None => splat(light, moved(scene.pivot), scene.marker_peak),
            }
        }
        if scene.hand {
            self.hand.iter_mut().for_each(|v| *v = 0.0);
            let radius = 0.06 * w.min(h) as f64;
            let lower = moved((mean[2], mean[3]));
            if let Some(palm) = scene.hand_at(t, lower, radius) {
                // Only the rows the arm crosses.
                let top = (palm.1 - radius - 1.0).max(0.0) as usize;
                let bottom = ((palm.1 + radius + 2.0) as usize).min(h);
                for y in top..bottom {
                    for x in 0..w {
                        self.hand[y * w + x] = hand_cover(x as f64, y as f64, palm, radius);
                    }
                }
                if scene.stickers.is_none() {
                    // In the dark, an arm faintly lit by the room's light.
                    for (l, a) in light.iter_mut().zip(&self.hand) {
                        *l += 30.0 * a;
                    }
                }
            }
        }
        let offset = self.rng.random_range(0..1 << 20);
        let edge = scene.table.unwrap_or(f64::INFINITY);
        let frame: Vec<u8> = match scene.stickers {
            None => light
                .iter()
                .enumerate()
                .flat_map(|(k, &l)| {
                    // The table: a dark surface in front of everything below its edge.
                    let l = if (k / w) as f64 >= edge {
                        scene.background as f32
                    } else {
                        l
                    };
                    let v = (l + self.noise[offset + k]).round().clamp(0.0, 255.0) as u8;
                    [v, v, v]
                })
                .collect(),
            Some([upper, lower]) => {
                // The board's grey under warm light, a hand before it, the stickers'
                // colours under the same light, each channel with its own noise.
                const BOARD: [f32; 3] = [178.0, 170.0, 156.0];
                const SKIN: [f32; 3] = [224.0, 172.0, 138.0];
                let pivot = scene.pivot_marker.unwrap_or([0; 3]);
                let n = self.noise.len() - w * h;
                let (cover, hand) = (&self.cover, &self.hand);
                (0..w * h)
                    .flat_map(|k| {
                        let shade = self.board[k];
                        let [a1, a2, a3] = [0, 1, 2].map(|m| cover[m][k].min(1.0));
                        let skin = hand.get(k).copied().unwrap_or(0.0);
                        let bare = (1.0 - a1 - a2 - a3).max(0.0);
                        let hidden = (k / w) as f64 >= edge;
                        (0..3).map(move |c| {
                            let v = if hidden {
                                scene.background as f32
                            } else {
                                let behind = (1.0 - skin) * BOARD[c] + skin * SKIN[c];
                                shade
                                    * (bare * behind
                                        + a1 * upper[c] as f32
                                        + a2 * lower[c] as f32
                                        + a3 * pivot[c] as f32)
                            };
                            (v, (offset + k + c * 7919) % n)
                        })
                    })
                    .map(|(v, at)| (v + self.noise[at]).round().clamp(0.0, 255.0) as u8)
                    .collect()
            }
        };
        // In view when all of the marker's light (to 3 sigma, over the whole streak) is
        // above the edge, hidden when all of it is below.
        let clear = 3.0 * sigma;
        let seen = |(top, bottom): (f64, f64)| match scene.table {
            None => Some(true),
            Some(e) if bottom + clear < e => Some(true),
            Some(e) if top - clear >= e => Some(false),
            Some(_) => None,
        };
        let truth = TruthRow {
            t,
            shift,
            m1: (mean[0], mean[1]),
            m2: (mean[2], mean[3]),
            seen1: seen(rows[0]),
            seen2: seen(rows[1]),
            metres: mean_m,
        };
        (frame, truth)
    }
}

/// A test film: `frames` frames rendered by [`Renderer`] and encoded as an H.264 MP4 at
/// `crf` into `path`; returns the truth of every frame (its pixels with the pivot where
/// the film's median frame shows it, where the picture wanders).
pub fn film(
    scene: &Scene,
    params: &Params,
    start: State,
    frames: usize,
    crf: u32,
    path: &std::path::Path,
) -> crate::Result<Vec<TruthRow>> {
    let mut renderer = Renderer::new(scene, params, start, frames);
    let mut truth = Vec::with_capacity(frames);
    let mut files = crate::render::Outputs::new();
    crate::video::write_mp4(
        &mut files,
        path,
        (scene.width, scene.height),
        crate::video::Mp4 {
            fps: scene.fps,
            crf,
        },
        "chaoscope test film",
        frames,
        |f| {
            let (rgb, row) = renderer.frame(f);
            truth.push(row);
            Ok(rgb)
        },
    )?;
    files.commit(&crate::monitor::Monitor::hidden())?;
    // A tracker measures from the pivot's marker at its median place: the truth's pixels
    // likewise (the wander about its median taken out).
    let median = |of: fn(&TruthRow) -> f64| {
        let mut v: Vec<f64> = truth.iter().map(of).collect();
        crate::stats::median(&mut v).unwrap_or(0.0)
    };
    let (mx, my) = (median(|r| r.shift.0), median(|r| r.shift.1));
    for r in &mut truth {
        r.m1 = (r.m1.0 + mx, r.m1.1 + my);
        r.m2 = (r.m2.0 + mx, r.m2.1 + my);
        r.shift = (r.shift.0 - mx, r.shift.1 - my);
    }
    Ok(truth)
}

/// How a tracker did against the truth.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Score {
    /// RMS distance (px) of the measured positions from the exposure's mean positions.
    pub rms: f64,
    /// The share of the masses wholly in view that were measured.
    pub found: f64,
    /// Positions given where the mass was wholly hidden.
    pub invented: usize,
    /// Positions nearer to the other mass than to the one named (the names swapped).
    pub swaps: usize,
    /// Positions more than 3 px from the named mass (a distractor followed).
    pub astray: usize,
    /// Masses partly hidden (by the table's edge), left out of the score.
    pub partial: usize,
}

/// Scores `found` (each frame's two positions in px, None where not seen) against `truth`.
pub fn score(found: &[[Option<(f64, f64)>; 2]], truth: &[TruthRow]) -> Score {
    assert_eq!(found.len(), truth.len(), "a row for every frame");
    let (mut sq, mut n, mut visible, mut measured) = (0.0, 0usize, 0usize, 0usize);
    let (mut invented, mut swaps, mut astray, mut partial) = (0, 0, 0, 0);
    let d = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
    for (r, t) in found.iter().zip(truth) {
        let true_at = [t.m1, t.m2];
        for (k, seen) in [t.seen1, t.seen2].into_iter().enumerate() {
            match (seen, r[k]) {
                (Some(true), Some(p)) => {
                    visible += 1;
                    measured += 1;
                    let e = d(p, true_at[k]);
                    if d(p, true_at[1 - k]) < e {
                        swaps += 1;
                    } else if e > 3.0 {
                        astray += 1;
                    } else {
                        sq += e * e;
                        n += 1;
                    }
                }
                (Some(true), None) => visible += 1,
                (Some(false), Some(_)) => invented += 1,
                (Some(false), None) => {}
                (None, _) => partial += 1,
            }
        }
    }
    Score {
        rms: (sq / n.max(1) as f64).sqrt(),
        found: measured as f64 / visible.max(1) as f64,
        invented,
        swaps,
        astray,
        partial,
    }
}

/// The share of `measured`'s coordinates (of masses wholly in view) within 1.96 of their
/// stated standard errors of the `truth`, both in metres along the world's axes as the CSV
/// states them: 95 % where the stated errors are the real ones and normal.
pub fn calibration(measured: &[super::CsvRow], truth: &[TruthRow]) -> f64 {
    let (mut inside, mut all) = (0usize, 0usize);
    for ((_, a, b), t) in measured.iter().zip(truth) {
        for (m, k, seen) in [(a, 0, t.seen1), (b, 2, t.seen2)] {
            if let (Some(m), Some(true)) = (m, seen) {
                for (e, sigma) in [(m.x - t.metres[k], m.sx), (m.y - t.metres[k + 1], m.sy)] {
                    all += 1;
                    inside += usize::from(e.abs() < 1.96 * sigma);
                }
            }
        }
    }
    inside as f64 / all.max(1) as f64
}
