//! From fields to files: colour maps, pictures of maps with the run's provenance, PNG and raw
//! .npy; every file written to a temporary name first and renamed, so no half-written output
//! is left behind.

mod annotate;
pub(crate) mod chart;
mod colormap;
mod exposure;
pub(crate) mod files;
mod legend;
mod maps;
pub mod store;

pub use annotate::{
    Annotated, Annotation, Axis, ColorBar, angle_ticks, annotate, decimal_ticks, register_font,
};
pub use colormap::{
    Colormap, FlipColors, NAN_RGB, NEVER_RGB, flip_colors, flip_kind_bar, flip_kind_colors,
    flip_kind_rgb, flip_table, ftle_colors, ftle_table,
};
pub use exposure::{Bobs, Canvas, Film, draw_arms};
pub use files::{
    Outputs, Png, check_writable, png_bytes, read_png, remove_pending, write_atomic, write_npy,
    write_npy_shaped, write_png,
};
pub use legend::legend;
pub use maps::{
    Drawn, Look, MapPicture, Picture, PictureSpec, UNRESOLVED_RGB, default_range, flip_picture,
    lyapunov_bar, lyapunov_picture, provenance,
};
