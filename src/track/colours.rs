//! A second sticker where one colour was given: a film of a red and a green sticker tracked
//! with one colour finds the masses in few frames; the colour the film also shows is named.

use super::detect::{COLOUR_NAMES, Markers, Scratch, chroma_direction, hue_cosine};

/// A marker colour as the markers are given: its name where it is a named one, else RRGGBB.
pub fn colour_name(rgb: [u8; 3]) -> String {
    COLOUR_NAMES.iter().find(|(_, c)| *c == rgb).map_or_else(
        || format!("{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2]),
        |(n, _)| n.to_string(),
    )
}

/// Frames kept to look for a second sticker where one colour was given.
pub const SAMPLED_FRAMES: usize = 8;

/// Where one colour (`given`) was given and the masses went unseen: the named colour more
/// than 90 degrees from `given` in hue whose sticker the `frames` show as well, in at least
/// three quarters of them, with at least a quarter of the `given` sticker's light (of those,
/// the brightest): the second sticker of a two-colour film. None where no colour is seen so.
pub fn second_colour(
    frames: &[Vec<u8>],
    width: usize,
    region: Option<(usize, usize, usize, usize)>,
    given: [u8; 3],
) -> Option<&'static str> {
    let mut scratch = Scratch::default();
    // The brightest blob of `colour` in `frame`: its light and where it is.
    let mut brightest = |colour: [u8; 3], frame: &[u8]| {
        Markers::Colour(colour)
            .find(frame, width, region, &mut scratch)
            .iter()
            .map(|b| (b.flux, b.x, b.y))
            .fold((0.0, 0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
    };
    let own: Vec<f64> = frames.iter().map(|f| brightest(given, f).0).collect();
    let mut best: Option<(f64, [u8; 3])> = None;
    for &(_, rgb) in COLOUR_NAMES
        .iter()
        .filter(|(_, c)| hue_cosine(*c, given) < 0.0)
    {
        let ratios: Vec<f64> = frames
            .iter()
            .zip(&own)
            .filter(|(_, o)| **o > 0.0)
            .map(|(f, o)| brightest(rgb, f).0 / o)
            .filter(|r| *r >= 0.25)
            .collect();
        let light: f64 = ratios.iter().sum();
        if 4 * ratios.len() >= 3 * frames.len().max(1) && best.is_none_or(|(b, _)| light > b) {
            best = Some((light, rgb));
        }
    }
    // Named by its own pixels' hue (a red sticker scores on pink's axis too).
    let (_, found) = best?;
    let mut sum = [0.0f32; 3];
    for f in frames {
        let (_, x, y) = brightest(found, f);
        let k = 3 * (y.round() as usize * width + x.round() as usize);
        if let Some(p) = f.get(k..k + 3) {
            let d = chroma_direction([p[0], p[1], p[2]]);
            (0..3).for_each(|c| sum[c] += d[c]);
        }
    }
    let along = |c: [u8; 3]| {
        let d = chroma_direction(c);
        d[0] * sum[0] + d[1] * sum[1] + d[2] * sum[2]
    };
    COLOUR_NAMES
        .iter()
        .filter(|(_, c)| hue_cosine(*c, given) < 0.0)
        .max_by(|a, b| along(a.1).total_cmp(&along(b.1)))
        .map(|(name, _)| *name)
}
