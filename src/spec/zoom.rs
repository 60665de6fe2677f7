//! A zoom's settings where none is given, read by every door (the CLI's flags, Python's
//! keywords, the explorer's `/api/zoom`), so that each is written once.

/// The film's frames, their rate and quality (H.264's constant rate factor), and the folder
/// for the frames and the film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZoomDefaults {
    pub frames: u32,
    pub fps: f64,
    pub crf: u32,
    pub output: &'static str,
}

pub const ZOOM: ZoomDefaults = ZoomDefaults {
    frames: 120,
    fps: 30.0,
    crf: 18,
    output: "out/zoom",
};
