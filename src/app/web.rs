//! `chaoscope web`: the explorer as a folder of static files that computes maps with WebGPU
//! on the viewer's own GPU ([`crate::web`] makes the files).

use std::io::Write;
use std::path::PathBuf;

use crate::error::Result;
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
