//! A flip-time map through the library, on the GPU when there is one, else the CPU:
//! `cargo run --release --example flip_map` writes out/example_flip.png.

use chaoscope::engine::{Backend, flip_map};
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::render::{Colormap, FlipColors, flip_colors, write_png};
use chaoscope::spec::{FlipSpec, Grid, Stepping};

fn main() -> Result<(), chaoscope::Error> {
    let spec = FlipSpec::new(
        Params::default(),
        Grid::square(256),
        Stepping {
            dt: 0.01,
            t_max: 20.0,
        },
    );
    let (map, info) = flip_map(&spec, Backend::Auto, &Monitor::hidden())?;
    let rgb = flip_colors(
        &map,
        FlipColors {
            t_lo: (1.0f64 / 9.81).sqrt(),
            t_max: 20.0,
            colormap: Colormap::Inferno,
        },
    );
    write_png(
        "out/example_flip.png".as_ref(),
        map.width,
        map.height,
        &rgb,
        &[],
    )?;
    let flipped = map.data.iter().filter(|t| t.is_finite()).count() as f64 / map.data.len() as f64;
    println!(
        "{} backend: {:.1} % of starts flip within 20 s -> out/example_flip.png",
        info.backend,
        100.0 * flipped
    );
    Ok(())
}
