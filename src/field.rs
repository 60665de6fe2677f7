//! What every map returns, whichever path made it.

/// A 2-D grid of f32 values, row-major, row 0 at the top of the image (theta2 at its maximum),
/// column 0 at theta1's minimum.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

impl Field {
    pub fn new(width: u32, height: u32, fill: f32) -> Self {
        Field {
            width,
            height,
            data: vec![fill; width as usize * height as usize],
        }
    }

    pub fn get(&self, col: u32, row: u32) -> f32 {
        self.data[row as usize * self.width as usize + col as usize]
    }
}
