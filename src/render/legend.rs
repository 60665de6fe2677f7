//! The explorer's legends, their words checked against the pictures' own colours.

use crate::field::Field;
use crate::model::Params;
use crate::spec::{FlipSpec, Grid, LyapunovSpec, MapKind};

use super::{MapPicture, PictureSpec};

/// The explorer's legend of `kind`: its table line's words, with the picture's dark and
/// bright ends named from the picture itself (two pixels, the low and the high end of its
/// colours, drawn as the kind draws a map and compared by luminance), so that the words
/// cannot disagree with the colours.
pub fn legend(kind: MapKind) -> String {
    let entry = kind.entry();
    if entry.low.is_empty() {
        return entry.legend.to_string();
    }
    let grid = Grid {
        width: 2,
        height: 1,
        ..Grid::square(1)
    };
    let stepping = crate::spec::Stepping {
        dt: 0.01,
        t_max: 10.0,
    };
    let flip = FlipSpec::new(Params::default(), grid, stepping);
    let drawn = match entry.indicator {
        // The flip times' colours run from the fastest flip to t-max.
        None => {
            let t_lo = super::FlipColors::t_lo(&flip.params) as f32;
            let field = Field {
                width: 2,
                height: 1,
                data: vec![t_lo, 0.99 * stepping.t_max as f32],
            };
            flip.draw(&field, &PictureSpec::default(), None, None)
        }
        Some(indicator) => {
            let spec = LyapunovSpec {
                indicator,
                ..LyapunovSpec::new(flip.params, grid, stepping)
            };
            let field = Field {
                width: 2,
                height: 1,
                data: vec![0.0, 1.0],
            };
            spec.draw(&field, &PictureSpec::default(), Some((0.0, 1.0)), None)
        }
    };
    let rgb = drawn.expect("two pixels draw").picture.rgb;
    let luminance = |p: &[u8]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let ends = match luminance(&rgb[..3]) < luminance(&rgb[3..6]) {
        true => format!("dark: {}; bright: {}", entry.low, entry.high),
        false => format!("dark: {}; bright: {}", entry.high, entry.low),
    };
    entry.legend.replace("{ends}", &ends)
}
