//! The README's flip-time map (docs/flip.png) through the library alone, no command line:
//! `cargo run --release --example flip_map` writes out/example_flip.png and says whether its
//! pixels equal the README's picture.

use chaoscope::engine::{Backend, Engine};
use chaoscope::model::Params;
use chaoscope::monitor::Monitor;
use chaoscope::render::{PictureSpec, flip_picture, read_png, write_png};
use chaoscope::spec::{FlipSpec, Grid, Stepping};

fn main() -> Result<(), chaoscope::Error> {
    let spec = FlipSpec::new(
        Params::default(),
        Grid::square(1024),
        Stepping {
            dt: 0.01,
            t_max: 30.0,
        },
    );
    spec.validate()?;
    let engine = Engine::new(Backend::Auto)?;
    if let Some(notice) = engine.notice() {
        eprintln!("{notice}");
    }
    let map = engine.map(&spec, &Monitor::hidden())?;
    let picture = flip_picture(&map, &spec, &PictureSpec::default(), None)?;
    let out = std::path::Path::new("out/example_flip.png");
    write_png(out, (picture.width, picture.height), &picture.rgb, &[])?;
    let flipped = map.data.iter().filter(|t| t.is_finite()).count() as f64 / map.data.len() as f64;
    let readme = read_png("docs/flip.png".as_ref())?;
    println!(
        "{} backend: {:.1} % of starts flip within 30 s -> {}; pixels {} docs/flip.png",
        engine.map_info(&spec.grid, spec.precision).backend(),
        100.0 * flipped,
        out.display(),
        if readme.rgb == picture.rgb {
            "equal to"
        } else {
            "differ from"
        }
    );
    Ok(())
}
