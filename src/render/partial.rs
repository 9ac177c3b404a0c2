//! Partial results: one frame's sums over a range of passes, with what makes merging them safe,
//! and the merge itself (Knaus & Zwicker 2011: passes are independent, so pass ranges rendered
//! anywhere add up to the whole run exactly).
//!
//! A partial file is `CAUSTIC-PARTIAL\n`, an 8-byte little-endian header length, a JSON header
//! ([`PartialHeader`]: the scene's SHA-256, the settings that shape every pass, the seed, the
//! frame, the pass range and the film's totals; JSON keeps f64 exactly), then the film's
//! per-pixel sums as little-endian f64 ([`Film::pixel_sums`]). It is written to a temporary file
//! and renamed, like every output.

use std::io::{Read, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::film::{Film, FilmMode, GUIDE_SUMS, PIXEL_SUMS};

/// The first bytes of a partial file.
const MAGIC: &[u8] = b"CAUSTIC-PARTIAL\n";

/// The largest header a partial file may have (a guard against reading garbage as a length).
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// What a partial result says about itself.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PartialHeader {
    /// The scene file, as given (for messages).
    pub scene: String,
    /// SHA-256 of the scene file and the files it references.
    pub scene_sha256: String,
    /// Everything that shapes a pass: resolution, photons, alpha, radius, seed, wavelength mode,
    /// spectral bands, shutter, lens.
    pub settings: serde_json::Value,
    /// The frame.
    pub frame: i32,
    /// The passes summed, `[first, end)`.
    pub passes: [u64; 2],
    /// The film's image size.
    pub size: [u32; 2],
    /// Film totals: the white estimate's XYZ sum, its luminance sum and square sum, and the
    /// non-finite estimates counted.
    pub white_xyz: [f64; 3],
    /// Sum of the passes' white luminance weights.
    pub white_y: f64,
    /// Sum of their squares.
    pub white_y_squared: f64,
    /// Estimates that were not finite.
    pub non_finite_estimates: u64,
}

/// A partial result read back.
pub struct Partial {
    /// Where it was read from.
    pub path: PathBuf,
    /// Its header.
    pub header: PartialHeader,
    /// Its sums.
    pub film: Film,
}

/// The partial file of `frame` for `passes` in `out_dir`.
pub fn partial_path(out_dir: &Path, frame: i32, passes: &Range<u64>) -> PathBuf {
    out_dir.join(format!("frame_{frame:04}.passes_{}-{}.partial", passes.start, passes.end))
}

/// SHA-256 of the scene file and of the files its JSON references by relative `uri` (buffers and
/// images), in order; a `.glb` is hashed whole.
pub fn scene_sha256(path: &Path) -> Result<String, String> {
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()));
    let bytes = read(path)?;
    let mut hash = Sha256::new();
    hash.update(&bytes);
    if let Ok(json) = serde_json::from_slice::<serde_json::Value>(&bytes) {
        let folder = path.parent().unwrap_or(Path::new("."));
        let uris = ["buffers", "images"]
            .into_iter()
            .flat_map(|key| json[key].as_array().cloned().unwrap_or_default());
        for uri in uris.filter_map(|v| v["uri"].as_str().map(str::to_owned)) {
            if !uri.starts_with("data:") {
                hash.update(read(&folder.join(&uri))?);
            }
        }
    }
    Ok(hash.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// Writes `film` (passes `header.passes`) to `path`, whole or not at all.
pub fn write(path: &Path, header: &PartialHeader, film: &Film) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let json = serde_json::to_vec(header).expect("a header serialises");
    let mut bytes = Vec::with_capacity(MAGIC.len() + 8 + json.len() + film.pixels.len() * 8 * PIXEL_SUMS);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(json.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&json);
    for value in film.pixel_sums() {
        bytes.extend_from_slice(&value.to_le_bytes());
    }
    crate::output::write_whole(path, |temporary| {
        let mut file = std::fs::File::create(temporary).map_err(fail)?;
        file.write_all(&bytes).and_then(|()| file.sync_all()).map_err(fail)
    })
}

/// The header of a film with `film`'s totals.
pub fn header(
    scene: &Path,
    scene_sha256: String,
    settings: serde_json::Value,
    frame: i32,
    passes: Range<u64>,
    film: &Film,
) -> PartialHeader {
    PartialHeader {
        scene: scene.display().to_string(),
        scene_sha256,
        settings,
        frame,
        passes: [passes.start, passes.end],
        size: [film.width, film.height],
        white_xyz: film.white_xyz.to_array(),
        white_y: film.white_y,
        white_y_squared: film.white_y_squared,
        non_finite_estimates: film.non_finite_estimates,
    }
}

/// Reads a partial file.
pub fn read(path: &Path) -> Result<Partial, String> {
    let fail = |what: &str| format!("{}: {what}", path.display());
    let mut file = std::fs::File::open(path).map_err(|e| fail(&format!("cannot open: {e}")))?;
    let mut magic = [0u8; MAGIC.len()];
    let mut length = [0u8; 8];
    file.read_exact(&mut magic)
        .and_then(|()| file.read_exact(&mut length))
        .ok()
        .filter(|()| magic == MAGIC)
        .ok_or_else(|| fail("not a Caustic partial result (written by `caustic render --partial`)"))?;
    let length = u64::from_le_bytes(length);
    if length > MAX_HEADER_BYTES {
        return Err(fail("damaged header"));
    }
    let mut json = vec![0u8; length as usize];
    file.read_exact(&mut json).map_err(|_| fail("truncated header"))?;
    let header: PartialHeader =
        serde_json::from_slice(&json).map_err(|e| fail(&format!("damaged header: {e}")))?;
    let mut body = Vec::new();
    file.read_to_end(&mut body).map_err(|e| fail(&format!("cannot read: {e}")))?;
    let film = film_of(&header, &body).ok_or_else(|| fail("truncated or damaged sums"))?;
    Ok(Partial { path: path.to_path_buf(), header, film })
}

/// The film a header and its little-endian f64 body describe.
fn film_of(header: &PartialHeader, body: &[u8]) -> Option<Film> {
    let settings = &header.settings;
    let mode = match settings["wavelength_nm"].as_f64() {
        Some(lambda_nm) => FilmMode::Monochromatic { lambda_nm: lambda_nm as f32 },
        None => FilmMode::Spectral,
    };
    let bins = settings["spectral_bins"].as_u64()? as usize;
    let guides = settings["denoising_passes"].as_bool().unwrap_or(false);
    let [width, height] = header.size;
    let per_pixel = PIXEL_SUMS + bins + if guides { GUIDE_SUMS } else { 0 };
    if u64::from(width) * u64::from(height) * 8 * per_pixel as u64 != body.len() as u64 {
        return None;
    }
    let mut film = Film::new(width, height, mode, bins, guides);
    let sums: Vec<f64> =
        body.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect();
    film.set_pixel_sums(&sums)?;
    film.white_xyz = DVec3::from_array(header.white_xyz);
    film.passes = header.passes[1] - header.passes[0];
    film.white_y = header.white_y;
    film.white_y_squared = header.white_y_squared;
    film.non_finite_estimates = header.non_finite_estimates;
    Some(film)
}

/// Merges one frame's partials: they must come from the same scene, settings and frame and
/// cover passes `0..n` without a gap or an overlap. Gives the film of passes `0..n`.
pub fn merge(mut partials: Vec<Partial>) -> Result<Film, String> {
    partials.sort_by_key(|p| p.header.passes);
    let first = partials.first().ok_or("no partial results to merge")?;
    for other in &partials[1..] {
        check_same_render(first, other)?;
    }
    let mut next = 0;
    for (i, p) in partials.iter().enumerate() {
        let [start, end] = p.header.passes;
        if start > next {
            return Err(format!(
                "frame {}: passes {next}..{start} are missing (no partial result covers them)",
                p.header.frame
            ));
        }
        if start < next {
            let before = &partials[i - 1];
            let [a, b] = before.header.passes;
            return Err(format!(
                "frame {}: {} (passes {a}..{b}) and {} (passes {start}..{end}) overlap",
                p.header.frame,
                before.path.display(),
                p.path.display()
            ));
        }
        next = end;
    }
    let mut partials = partials.into_iter();
    let mut film = partials.next().expect("one partial at least").film;
    for p in partials {
        film.add(&p.film);
    }
    Ok(film)
}

/// Whether `b` belongs with `a`: same scene, settings (seed included) and frame.
fn check_same_render(a: &Partial, b: &Partial) -> Result<(), String> {
    let (ha, hb) = (&a.header, &b.header);
    let differ = |what: &str, x: &dyn std::fmt::Display, y: &dyn std::fmt::Display| {
        format!(
            "{} and {} do not belong together: {what} differ ({x} vs {y})",
            a.path.display(),
            b.path.display()
        )
    };
    if ha.scene_sha256 != hb.scene_sha256 {
        return Err(differ("their scenes", &ha.scene, &hb.scene));
    }
    if ha.frame != hb.frame {
        return Err(differ("their frames", &ha.frame, &hb.frame));
    }
    if ha.settings != hb.settings {
        let keys =
            ha.settings.as_object().into_iter().flatten().filter(|(k, v)| hb.settings.get(*k) != Some(*v));
        let named: Vec<String> = keys.map(|(k, v)| format!("{k} {v} vs {}", hb.settings[k])).collect();
        return Err(format!(
            "{} and {} do not belong together: their settings differ ({})",
            a.path.display(),
            b.path.display(),
            named.join(", ")
        ));
    }
    Ok(())
}
