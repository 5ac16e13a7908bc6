//! The error map as a PNG heat map (black is equal, bright is different),
//! written atomically through `crate::safe_files`.

use super::*;

/// FLIP's own magma colour map, 256 entries of 8-bit sRGB, taken from the
/// FLIP library so our error maps look exactly like those of FLIP's tools.
pub(super) fn magma_lut() -> Vec<[u8; 3]> {
    nv_flip::magma_lut()
        .to_vec()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Black-red-yellow-white ramp for RMSE/PSNR maps. Deliberately not magma, so
/// nobody mistakes a relative heat map for FLIP's absolute scale.
pub(super) const HEAT: [(u8, [u8; 3]); 4] = [
    (0, [0, 0, 0]),
    (85, [255, 0, 0]),
    (170, [255, 255, 0]),
    (255, [255, 255, 255]),
];

/// Expands control points (ascending indices, first 0, last 255) into a
/// 256-entry table by linear interpolation.
pub(super) fn build_lut(points: &[(u8, [u8; 3])]) -> Vec<[u8; 3]> {
    (0..=255u8)
        .map(|i| {
            // First segment whose end is at or past i; the clamp keeps a
            // malformed table from indexing out of range.
            let k = points.windows(2).position(|w| i <= w[1].0).unwrap_or(0);
            let ((i0, lo), (i1, hi)) = match (points.get(k), points.get(k + 1)) {
                (Some(&a), Some(&b)) => (a, b),
                (Some(&a), None) => (a, a),
                _ => return [0, 0, 0],
            };
            let span = f64::from(i1) - f64::from(i0);
            let f = if span > 0.0 {
                ((f64::from(i) - f64::from(i0)) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            std::array::from_fn(|c| {
                (f64::from(lo[c]) + f * (f64::from(hi[c]) - f64::from(lo[c]))).round() as u8
            })
        })
        .collect()
}

/// Writes `cmp.error_map` as an RGB PNG at `path`.
///
/// FLIP maps are coloured with FLIP's magma map on its absolute `[0, 1]`
/// scale, so pictures from different runs are comparable. RMSE/PSNR maps are
/// a heat map (black, red, yellow, white) normalised to the map's maximum, so
/// even tiny differences are visible; an all-zero map is black.
///
/// The PNG is written to a temporary file in the same folder and renamed into
/// place, so a failed write never leaves a partial or stale-looking file at
/// `path`.
pub fn write_diff_png(cmp: &ImageDiff, path: &Path) -> Result<(), CompareError> {
    let expected = (cmp.width as usize).checked_mul(cmp.height as usize);
    if cmp.width == 0 || cmp.height == 0 || expected != Some(cmp.error_map.len()) {
        return Err(CompareError::BadErrorMap {
            path: path.to_owned(),
            len: cmp.error_map.len(),
            width: cmp.width,
            height: cmp.height,
        });
    }

    let (lut, scale) = match cmp.metric {
        Metric::Flip => (magma_lut(), 1.0f32),
        Metric::Rmse | Metric::Psnr => {
            let max = cmp.error_map.iter().copied().fold(0.0f32, f32::max);
            let scale = if max > 0.0 && max.is_finite() {
                1.0 / max
            } else {
                0.0
            };
            (build_lut(&HEAT), scale)
        }
    };
    let mut rgb = Vec::with_capacity(cmp.error_map.len() * 3);
    for &v in &cmp.error_map {
        let t = v * scale;
        // NaN fails both comparisons and lands on index 0.
        let t = if t > 0.0 { t.min(1.0) } else { 0.0 };
        rgb.extend_from_slice(&lut[(t * 255.0).round() as usize]);
    }

    write_atomically(path, |w| {
        PngEncoder::new(w)
            .write_image(&rgb, cmp.width, cmp.height, ExtendedColorType::Rgb8)
            .map_err(|source| CompareError::Encode {
                path: path.to_owned(),
                source,
            })
    })
}

/// Writes through `write` into a temporary file for `path` and renames it
/// into place ([`crate::safe_files`], the crate's one file writer); on any
/// failure the temporary file is removed. The sweep report writes its files
/// through `crate::safe_files` directly.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), CompareError>,
) -> Result<(), CompareError> {
    let io_err = |source| CompareError::Write {
        path: path.to_owned(),
        source,
    };
    let as_io = |e: crate::safe_files::FileError| match e {
        crate::safe_files::FileError::Io { error, .. } => io_err(error),
        refused => io_err(io::Error::other(refused.to_string())),
    };
    crate::safe_files::check_output(path, crate::safe_files::Format::Png).map_err(as_io)?;
    let pending = crate::safe_files::PendingFile::create(path).map_err(as_io)?;
    let mut w = BufWriter::new(pending.file().try_clone().map_err(io_err)?);
    write(&mut w)?;
    w.flush().map_err(io_err)?;
    drop(w);
    pending.commit().map_err(as_io)?;
    Ok(())
}
