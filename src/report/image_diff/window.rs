//! The worst window: the error pooled over every square of `WINDOW` x
//! `WINDOW` pixels, which catches changes too small for the 99th
//! percentile (absolute for FLIP, relative to the reference's level for
//! RMSE and PSNR).

use super::*;

/// The largest `score` over all [`WINDOW`]x[`WINDOW`] squares inside a
/// `width` x `height` image (clipped to the image size), where `score` gets
/// the sums over the square of the `N` per-pixel values that `value` gives
/// for a row-major pixel index, and the number of pixels in the square.
///
/// Keeps running column sums, so it needs memory for one row rather than a
/// summed-area table of the whole image.
pub(super) fn worst_window<const N: usize>(
    width: u32,
    height: u32,
    value: impl Fn(usize) -> [f64; N],
    score: impl Fn([f64; N], f64) -> f64,
) -> f64 {
    let (w, h) = (width as usize, height as usize);
    let (kx, ky) = (w.min(WINDOW as usize), h.min(WINDOW as usize));
    let count = (kx * ky) as f64;
    let add = |a: &mut [f64; N], b: [f64; N], sign: f64| {
        for (x, y) in a.iter_mut().zip(b) {
            *x += sign * y;
        }
    };
    // columns[x]: sums over the last ky rows of column x.
    let mut columns = vec![[0.0; N]; w];
    let mut worst = 0.0f64;
    for y in 0..h {
        for (x, column) in columns.iter_mut().enumerate() {
            add(column, value(y * w + x), 1.0);
            if y >= ky {
                add(column, value((y - ky) * w + x), -1.0);
            }
        }
        if y + 1 < ky {
            continue;
        }
        let mut sums = [0.0; N];
        for (x, &column) in columns.iter().enumerate() {
            add(&mut sums, column, 1.0);
            if x >= kx {
                add(&mut sums, columns[x - kx], -1.0);
            }
            if x + 1 >= kx {
                // Running sums of non-negative values can come out a hair
                // below zero after subtractions; clamp so a score never
                // turns NaN from a negative square root.
                let s = sums.map(|v| v.max(0.0));
                worst = worst.max(score(s, count));
            }
        }
    }
    worst
}

/// `worst_window` for RMSE and PSNR: the mean per-pixel error over the
/// window divided by the reference's mean level there or over the whole
/// image, whichever is larger (a pixel's level is the RMS of its R, G, B).
/// The floor keeps a faint change in a nearly black window, such as one edge
/// pixel against a black background, from counting as a huge relative
/// error; an all-black reference uses a level of 1. `reference` is
/// interleaved RGB, `map` the per-pixel RMS error.
pub(super) fn relative_worst_window(
    reference: &[f32],
    map: &[f32],
    width: u32,
    height: u32,
) -> f64 {
    let level = |i: usize| {
        (reference[3 * i..3 * i + 3]
            .iter()
            .map(|&v| f64::from(v) * f64::from(v))
            .sum::<f64>()
            / 3.0)
            .sqrt()
    };
    let overall = (0..map.len()).map(level).sum::<f64>() / map.len() as f64;
    let floor = if overall > 0.0 { overall } else { 1.0 };
    worst_window(
        width,
        height,
        |i| [f64::from(map[i]), level(i)],
        |[err, reference], n| (err / n) / (reference / n).max(floor),
    )
}
