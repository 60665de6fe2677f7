//! What the paths return, whichever made it: maps ([`Field`]) and convergence runs, and
//! which path made them ([`RunInfo`]): the ground floor the engine, the render and the files
//! all stand on.

/// The floating-point precision a GPU kernel integrates in (the CPU path is always f64).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Precision {
    /// The default: every GPU, fastest.
    #[default]
    F32,
    /// Needs an adapter with f64 (`Features::SHADER_F64`; lavapipe has it).
    F64,
}

impl Precision {
    pub const ALL: [Precision; 2] = [Precision::F32, Precision::F64];

    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }

    /// A GPU path in this precision, in the PNG metadata's words.
    pub fn gpu_path_name(self) -> &'static str {
        match self {
            Precision::F32 => "gpu",
            Precision::F64 => "gpu f64",
        }
    }
}

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

    /// Fills rows `rows..height` from the ones above by point reflection through the centre:
    /// (col, row) takes the value of (width-1-col, height-1-row). Needs rows >= height / 2.
    pub fn mirror_below(&mut self, rows: u32) {
        mirror_below(&mut self.data, self.width as usize, rows as usize);
    }
}

/// [`Field::mirror_below`] for rows of any values (`width` a row), e.g. a verdict's mask.
pub fn mirror_below<T: Copy>(data: &mut [T], width: usize, rows: usize) {
    let h = data.len() / width.max(1);
    for row in rows..h {
        let (above, below) = data.split_at_mut(row * width);
        let source = &above[(h - 1 - row) * width..(h - row) * width];
        for (out, v) in below[..width].iter_mut().zip(source.iter().rev()) {
            *out = *v;
        }
    }
}

/// Running FTLE estimates of one start: `ftle[i]` (1/s) is the mean log stretch rate over
/// `[0, t[i]]`, one entry per renormalisation; the last is the exponent at t-max.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Convergence {
    pub t: Vec<f64>,
    pub ftle: Vec<f64>,
}

impl Convergence {
    pub fn last(&self) -> f64 {
        self.ftle.last().copied().unwrap_or(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Field;

    #[test]
    fn mirror_below_reflects_through_the_centre() {
        // 3 x 3, rows 0 and 1 computed: row 2 is row 0 reversed; the middle row stays.
        let mut f = Field {
            width: 3,
            height: 3,
            data: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0, 0.0, 0.0],
        };
        f.mirror_below(2);
        assert_eq!(f.data, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 3.0, 2.0, 1.0]);
        let mut g = Field {
            width: 2,
            height: 4,
            data: vec![1.0, 2.0, 3.0, 4.0, 0.0, 0.0, 0.0, 0.0],
        };
        g.mirror_below(2);
        assert_eq!(g.data, [1.0, 2.0, 3.0, 4.0, 4.0, 3.0, 2.0, 1.0]);
    }
}

/// The path a run takes: a type, so that what depends on it (the f32 tolerance floor, the
/// words in the PNG and the summary) is decided once, from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// The f64 CPU reference.
    Cpu,
    /// A GPU kernel in this precision.
    Gpu(Precision),
    /// Read back from a Zarr store (`render`).
    Store,
}

impl Path {
    /// The path in the PNG metadata's words: "cpu", "gpu", "gpu f64", "zarr store".
    pub fn name(self) -> &'static str {
        match self {
            Path::Cpu => "cpu",
            Path::Gpu(precision) => precision.gpu_path_name(),
            Path::Store => "zarr store",
        }
    }

    pub fn on_gpu(self) -> bool {
        matches!(self, Path::Gpu(_))
    }

    /// The precision the arithmetic runs in (the CPU's, and a store's maps', is f64).
    pub fn precision(self) -> Precision {
        match self {
            Path::Gpu(precision) => precision,
            Path::Cpu | Path::Store => Precision::F64,
        }
    }
}

/// Which path a run took, for the user and the PNG metadata.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    pub path: Path,
    pub adapter: Option<String>,
}

impl RunInfo {
    pub const CPU: RunInfo = RunInfo {
        path: Path::Cpu,
        adapter: None,
    };

    /// The path in the PNG metadata's words ([`Path::name`]).
    pub fn backend(&self) -> &'static str {
        self.path.name()
    }

    /// Where it ran, in words: the adapter's name or "the CPU".
    pub fn place(&self) -> &str {
        self.adapter.as_deref().unwrap_or("the CPU")
    }
}
