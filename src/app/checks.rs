//! Checks of values and output paths that every command makes before any work, and text
//! outputs written atomically or to standard output.

use std::path::Path;

use crate::error::{Error, Result, check_within};
use crate::monitor::Monitor;
use crate::render::{Outputs, check_writable};

/// A CSV (or any text) into `output`, atomically, or to `stdout` when there is none.
pub fn write_text(
    output: Option<&Path>,
    stdout: &mut dyn std::io::Write,
    monitor: &Monitor,
    write: impl Fn(&mut dyn std::io::Write) -> Result<()>,
) -> Result<()> {
    match output {
        Some(path) => {
            let mut files = Outputs::new();
            files.write(path, |w| write(w))?;
            files.commit(monitor)
        }
        None => write(stdout),
    }
}

/// An output file `path` given as `field`: the right extension and a place it can be
/// written, checked before any work.
pub fn check_output(field: &'static str, path: &Path, ext: &str) -> Result<()> {
    check_extension(field, path, ext)?;
    check_writable(field, path)
}

/// The file `path` names, for comparing names: links and `..` resolved as far as the path
/// exists, the rest resolved lexically (as the run will make it).
fn identity(path: &Path) -> std::path::PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    // Component by component: what exists through its links, the rest (a folder the run has
    // not made yet, which holds no links) lexically, so `z/../z/f` is `z/f` before `z` is.
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = std::path::PathBuf::new();
    for c in absolute.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            c => {
                out.push(c);
                if let Ok(real) = out.canonicalize() {
                    out = real;
                }
            }
        }
    }
    out
}

/// No two of a run's `outputs`, and no output and one of its `inputs`, are one file (by
/// name, through links): the later write would replace the earlier, or the input. The error
/// names the later output's field and the other's. Each path is resolved once and looked up
/// in a set, so a film's 100,001 files are checked in linear time.
pub fn check_distinct(
    outputs: &[(&'static str, &Path)],
    inputs: &[(&'static str, &Path)],
) -> Result<()> {
    let mut read = std::collections::HashMap::with_capacity(inputs.len());
    for (field, path) in inputs {
        read.entry(identity(path)).or_insert(*field);
    }
    let mut written = std::collections::HashMap::with_capacity(outputs.len());
    for (field, path) in outputs {
        let name = identity(path);
        let same = |other: &'static str, input| Error::SameFile {
            field,
            other,
            path: path.to_path_buf(),
            input,
        };
        if let Some(&other) = written.get(&name) {
            return Err(same(other, false));
        }
        if let Some(&other) = read.get(&name) {
            return Err(same(other, true));
        }
        written.insert(name, *field);
    }
    Ok(())
}

/// The files `names` a run writes into the directory `dir` (given as `field`): the folder
/// one that takes files (probed once), each file one that may be replaced, none of them one
/// of the run's `inputs`, and none one of its outputs elsewhere, `also` (a film).
pub fn check_directory(
    field: &'static str,
    dir: &Path,
    names: &[impl AsRef<Path>],
    also: &[(&'static str, &Path)],
    inputs: &[(&'static str, &Path)],
) -> Result<()> {
    let paths: Vec<_> = names.iter().map(|n| dir.join(n)).collect();
    if let Some(first) = paths.first() {
        check_writable(field, first)?;
    }
    for path in &paths {
        crate::render::files::replaceable(path)
            .map_err(|why| Error::invalid(field, format!("{}: {why}", path.display())))?;
    }
    let named: Vec<_> = paths
        .iter()
        .map(|p| (field, p.as_path()))
        .chain(also.iter().copied())
        .collect();
    check_distinct(&named, inputs)
}

/// The files a run on tracked data reads: the data (`file`) and a parameter file, if any.
pub fn tracked_inputs<'a>(
    file: &'a Path,
    params: &'a crate::params::ParamSources,
) -> Vec<(&'static str, &'a Path)> {
    let mut inputs = vec![("file", file)];
    inputs.extend(params.params.as_deref().map(|p| ("params", p)));
    inputs
}

/// `path` must end in `.ext`, else an error naming `field`.
pub fn check_extension(field: &'static str, path: &Path, ext: &str) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case(ext) => Ok(()),
        _ => Err(Error::invalid(
            field,
            format!("{} must end in .{ext}", path.display()),
        )),
    }
}

/// `fit` and `forecast` fit both joints' damping to the data: a value given for it by the
/// flag would be written into the reproducing command, yet change nothing. A parameter
/// file's (a model `fit` wrote) is one of the fit's starts, and said so.
pub fn check_damping_not_given(params: &crate::params::ParamSources) -> Result<()> {
    if params.joint_damping.is_some() {
        return Err(Error::invalid(
            "joint_damping",
            "is fitted to the data here; leave it out",
        ));
    }
    Ok(())
}

/// A tracked file's units: a frame rate and a pixel scale within what cameras do.
pub fn check_units(units: &crate::fit::data::Units) -> Result<()> {
    if let Some(rate) = units.frame_rate {
        check_within("frame_rate", rate, 1e-3, 1e7)?;
    }
    if let Some(crate::fit::data::PixelScale::PerMetre(p)) = units.pixels_per_metre {
        check_within("pixels_per_metre", p, 1e-3, 1e9)?;
    }
    if units.y_up && units.pixels_per_metre.is_none() {
        return Err(Error::invalid(
            "y_up",
            "is for pixels (with [[pixels_per_metre]]): positions in metres are read with y up already",
        ));
    }
    Ok(())
}
