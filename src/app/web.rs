//! `chaoscope web`: the explorer as a folder of static files that computes maps with WebGPU
//! on the viewer's own GPU ([`crate::web`] makes the files).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::monitor::Monitor;
use crate::render::Outputs;
use crate::web::{SiteSpec, files};

#[derive(Clone, Debug)]
pub struct WebJob {
    pub site: SiteSpec,
    /// The folder the site goes into.
    pub output: PathBuf,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct WebSummary {
    pub output: PathBuf,
    pub files: Vec<PathBuf>,
    /// The site's size in bytes.
    pub bytes: u64,
    pub pendulums: Vec<String>,
}

/// Writes the site into its folder, every file staged and renamed into place together.
pub fn run(job: &WebJob, monitor: &Monitor) -> Result<WebSummary> {
    for p in &job.site.pendulums {
        crate::spec::validate_params(&p.params)?;
    }
    let site = files(&job.site);
    let names: Vec<&str> = site.iter().map(|(name, _)| name.as_str()).collect();
    check_folder(&job.output)?;
    super::checks::check_directory("output", &job.output, &names, &[], &[])?;
    std::fs::create_dir_all(&job.output)?;
    let mut outputs = Outputs::new();
    for (name, bytes) in &site {
        outputs.write(&job.output.join(name), |w| {
            w.write_all(bytes).map_err(crate::Error::Io)
        })?;
    }
    outputs.commit(monitor)?;
    Ok(WebSummary {
        output: job.output.clone(),
        files: names.iter().map(|n| job.output.join(n)).collect(),
        bytes: site.iter().map(|(_, b)| b.len() as u64).sum(),
        pendulums: job.site.pendulums.iter().map(|p| p.name.clone()).collect(),
    })
}

/// The folder takes the site if it is new, empty, or holds a site `chaoscope web` wrote (its
/// manifest.json says so): any other folder's files would be mixed with the site's, and a
/// page of the user's called index.html replaced. A link to nothing is named as such.
fn check_folder(dir: &Path) -> Result<()> {
    if dir.symlink_metadata().is_ok() && !dir.exists() {
        return Err(Error::invalid(
            "output",
            format!(
                "{} is a link to nothing (dangling): give a folder, or remove the link",
                dir.display()
            ),
        ));
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        // New (made below), or not a folder: the file checks say which.
        return Ok(());
    };
    // A few names are enough to say what the folder holds; a huge folder is not listed.
    let held: Vec<String> = entries
        .take(1000)
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if held.is_empty() || is_site(&dir.join("manifest.json")) {
        return Ok(());
    }
    let mut shown: Vec<&str> = held.iter().map(String::as_str).collect();
    shown.sort_unstable();
    let more = shown.len().saturating_sub(5);
    shown.truncate(5);
    Err(Error::invalid(
        "output",
        format!(
            "{} holds files `chaoscope web` did not write ({}{}): give a new or empty folder, or one a site was written into before",
            dir.display(),
            shown.join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            }
        ),
    ))
}

/// Whether `manifest` is a site's manifest (read within its bound): the generator this
/// writes, or a site's version and kernels as earlier versions wrote them.
fn is_site(manifest: &Path) -> bool {
    let Ok(text) = crate::input::read_text("output", manifest, crate::input::METADATA_CAP) else {
        return false;
    };
    let Ok(m) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    m["generator"] == crate::web::GENERATOR
        || (m["version"].is_string() && m["kernels"].is_object())
}
