//! The library's one error type: variants a caller can act on.

/// Everything that can go wrong in a run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No GPU adapter could be found.
    #[error(
        "no GPU adapter found: install a Vulkan driver (on Debian: apt-get install mesa-vulkan-drivers) or use the CPU backend"
    )]
    NoAdapter,
    /// A value is outside what the run can accept. `field` names the specification's field
    /// (`t_max`, `size`, `joint_damping`...); the command line maps it to its flag.
    #[error("invalid value for {field}: {reason}")]
    InvalidSpec { field: &'static str, reason: String },
    /// An input file (named by `field`) that does not exist.
    #[error("invalid value for {field}: {}: no such file", path.display())]
    Missing {
        field: &'static str,
        path: std::path::PathBuf,
    },
    /// Two files of one run (named by `field` and `other`) that are one file: the later
    /// output would replace the earlier one, or the input `other` names.
    #[error("invalid value for {field}: {} is also the {other} file {}", path.display(), match *input { true => "this run reads: writing it would replace it", false => "of this run: each output needs a file of its own" })]
    SameFile {
        field: &'static str,
        other: &'static str,
        path: std::path::PathBuf,
        input: bool,
    },
    /// A store (named by `field`) made with other settings than this run's: each setting
    /// (a spec field) that differs, with the store's value and this run's.
    #[error("invalid value for {field}: {} was made with other settings: {} (its command: {command})", path.display(), describe(differences))]
    StoreDiffers {
        field: &'static str,
        path: std::path::PathBuf,
        differences: Vec<(&'static str, String, String)>,
        command: String,
    },
    /// A program a run needs (FFmpeg for films) is not installed.
    #[error("{what} needs {tool}: install FFmpeg (on Debian: {install})")]
    MissingTool {
        tool: &'static str,
        what: &'static str,
        /// How to install it, as the room that runs it says.
        install: &'static str,
    },
    /// The GPU reported an error (validation, out of memory, lost device).
    #[error("GPU error: {0}")]
    Gpu(String),
    /// Drawing a plot or an annotation failed.
    #[error("plotting: {0}")]
    Plot(String),
    /// Encoding or decoding a file format (PNG, GIF, JSON) failed.
    #[error("{0}")]
    Format(String),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    File {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    /// The user interrupted the run (Ctrl-C).
    #[error("interrupted")]
    Interrupted,
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// "t_max 1 there, 2 here; ..." for [`Error::StoreDiffers`].
fn describe(differences: &[(&'static str, String, String)]) -> String {
    differences
        .iter()
        .map(|(field, theirs, ours)| format!("{field} {theirs} there, {ours} here"))
        .collect::<Vec<_>>()
        .join("; ")
}

impl Error {
    /// An invalid value of the specification field `field`.
    pub fn invalid(field: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidSpec {
            field,
            reason: reason.into(),
        }
    }

    /// The same error, naming `to` where it named the field `from` (a door whose keyword
    /// for a field differs: `traces` calls `t_max` its exposure).
    pub fn renamed(self, from: &str, to: &'static str) -> Self {
        match self {
            Error::InvalidSpec { field, reason } if field == from => {
                Error::InvalidSpec { field: to, reason }
            }
            e => e,
        }
    }

    /// The same error as the fault of the input file that `field` names: one that is not
    /// there is [`Error::Missing`], one that cannot be read as what it should be (a folder, a
    /// FIFO, text for a film, a film cut short) an invalid value of `field`; any other error
    /// (a missing program, an interruption) as it is.
    pub fn as_input(self, field: &'static str) -> Self {
        match self {
            Error::File { path, source } if source.kind() == std::io::ErrorKind::NotFound => {
                Error::Missing { field, path }
            }
            e @ (Error::File { .. } | Error::Format(_)) => Error::invalid(field, e.to_string()),
            e => e,
        }
    }

    /// A plotting error (plotters' errors carry the backend's error type).
    pub fn plot(e: impl std::fmt::Debug) -> Self {
        Error::Plot(format!("{e:?}"))
    }

    /// A file-format error, with the file it concerns.
    pub fn format(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        Error::Format(format!("{}: {e}", path.display()))
    }
}

/// `text` with every setting it names, `[[field]]` or `[[field=value]]` (a spec field and the
/// value to give it), worded by `word(field, value)`: the library names fields, each door
/// words them (the CLI `--precision f64`, Python `precision='f64'`, the explorer
/// `precision=f64`). Messages and notices name settings this way and no door's flag.
pub fn spell(text: &str, word: impl Fn(&str, Option<&str>) -> String) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("[[") {
        let Some(len) = rest[start + 2..].find("]]") else {
            break;
        };
        let inner = &rest[start + 2..start + 2 + len];
        out.push_str(&rest[..start]);
        out.push_str(&match inner.split_once('=') {
            Some((field, value)) => word(field, Some(value)),
            None => word(inner, None),
        });
        rest = &rest[start + 2 + len + 2..];
    }
    out.push_str(rest);
    out
}

/// `v` finite and > 0, else an error naming `field`.
pub(crate) fn finite_positive(field: &'static str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("{v} is not allowed; it must be a finite number > 0"),
        ))
    }
}

/// `v` within [lo, hi], else an error naming `field`.
pub fn check_within(field: &'static str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("{v} must be in [{lo}, {hi}]"),
        ))
    }
}

/// A count within [lo, hi], else an error naming `field`.
pub fn check_count(field: &'static str, n: u64, lo: u64, hi: u64) -> Result<()> {
    if (lo..=hi).contains(&n) {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!("must be between {lo} and {hi}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_door_words_the_settings_a_message_names() {
        // A door that writes <field value>.
        let cli = |f: &str, v: Option<&str>| match v {
            Some(v) => format!("<{f} {v}>"),
            None => format!("<{f}>"),
        };
        assert_eq!(
            super::spell("take [[precision=f64]] or widen [[t_max]]; [not one]", cli),
            "take <precision f64> or widen <t_max>; [not one]"
        );
        assert_eq!(super::spell("no setting", cli), "no setting");
        assert_eq!(super::spell("open [[end", cli), "open [[end");
    }
}
