//! The library's one error type: variants a caller can act on.

/// Everything that can go wrong in a run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No GPU adapter could be found.
    #[error(
        "no GPU adapter found: install a Vulkan driver (on Debian: apt-get install mesa-vulkan-drivers) or use --backend cpu"
    )]
    NoAdapter,
    /// A value is outside what the run can accept; `flag` names the command-line flag.
    #[error("invalid value for {flag}: {reason}")]
    InvalidSpec { flag: &'static str, reason: String },
    /// The GPU reported an error (validation, out of memory, lost device).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// The user interrupted the run (Ctrl-C).
    #[error("interrupted")]
    Interrupted,
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn invalid(flag: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidSpec {
            flag,
            reason: reason.into(),
        }
    }
}
