//! The farm's merge: partial results of pass ranges added up into whole frames.

use std::path::{Path, PathBuf};

use super::partial;
use super::report::write_frame;
use super::settings::frame_path;
use crate::film::Film;

/// Adds up partial results into `OUT/frame_####.exr`, one per frame they hold, with the error
/// passes a whole run writes; gives each EXR with its merged film.
pub fn merge(paths: &[PathBuf], out_dir: &Path, confidence: f64) -> Result<Vec<(PathBuf, Film)>, String> {
    let mut by_frame: std::collections::BTreeMap<i32, Vec<partial::Partial>> = Default::default();
    for path in paths {
        let p = partial::read(path)?;
        by_frame.entry(p.header.frame).or_default().push(p);
    }
    std::fs::create_dir_all(out_dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", out_dir.display()))?;
    let mut written = Vec::new();
    for (frame, partials) in by_frame {
        let film = partial::merge(partials)?;
        let path = frame_path(out_dir, frame);
        write_frame(&film, &crate::error::pixel_errors(&film, confidence), &path)?;
        written.push((path, film));
    }
    Ok(written)
}
