//! Separable Gaussian blur with nearest (clamp) border handling, in 2D and 3D.
//!
//! The kernel matches `scipy.ndimage.gaussian_filter` with its default
//! `truncate = 4.0` and `mode = "nearest"`: radius `⌊4σ + 0.5⌋`, weights
//! `exp(-x² / 2σ²)` normalised to sum 1. Every pass of a large image is
//! parallel over rows (rayon); sums are accumulated in `f64`.

use rayon::prelude::*;

/// Normalised 1D Gaussian kernel of standard deviation `sigma` (pixels),
/// truncated at `⌊4σ + 0.5⌋` like SciPy; length `2·radius + 1`.
/// Returns `[1.0]` for `sigma <= 0`.
pub fn gaussian_kernel(sigma: f64) -> Vec<f64> {
    if sigma <= 0.0 || !sigma.is_finite() {
        return vec![1.0];
    }
    let radius = (4.0 * sigma + 0.5) as i64;
    let mut k: Vec<f64> = (-radius..=radius)
        .map(|x| (-0.5 / (sigma * sigma) * (x * x) as f64).exp())
        .collect();
    let sum = numpy_sum(&k);
    k.iter_mut().for_each(|w| *w /= sum);
    k
}

/// Gaussian blur of a row-major `width × height` image (standard deviation
/// `sigma` pixels, clamp border). Returns a new image; `sigma <= 0` copies.
pub fn gaussian_blur_2d(image: &[f32], width: usize, height: usize, sigma: f64) -> Vec<f32> {
    gaussian_blur_3d(image, width, height, 1, sigma)
}

/// Gaussian blur of an `nx × ny × nz` volume stored with x fastest
/// (standard deviation `sigma` voxels, clamp border). Returns a new volume;
/// `sigma <= 0` copies. Axes of extent 1 are skipped, so `nz = 1` is 2D.
pub fn gaussian_blur_3d(image: &[f32], nx: usize, ny: usize, nz: usize, sigma: f64) -> Vec<f32> {
    blur(image, [nx, ny, nz], sigma)
}

/// [`gaussian_blur_3d`] on `f64` samples (used by the phantom renderer so
/// that noise-free renders agree with the `f64` SciPy pipeline).
pub fn gaussian_blur_3d_f64(
    image: &[f64],
    nx: usize,
    ny: usize,
    nz: usize,
    sigma: f64,
) -> Vec<f64> {
    blur(image, [nx, ny, nz], sigma)
}

/// A sample type the passes read and write; they sum in `f64` either way.
trait Sample: Copy + Send + Sync {
    fn wide(self) -> f64;
    fn narrow(v: f64) -> Self;
}

impl Sample for f32 {
    fn wide(self) -> f64 {
        self as f64
    }
    fn narrow(v: f64) -> Self {
        v as f32
    }
}

impl Sample for f64 {
    fn wide(self) -> f64 {
        self
    }
    fn narrow(v: f64) -> Self {
        v
    }
}

/// The blur of `image`, an `nx × ny × nz` volume: the first pass reads the
/// input and the last writes the output in their own type, the passes
/// between them keep `f64` (so an `f32` image is blurred as its `f64` copy
/// would be, to the bit, without the copy).
fn blur<S: Sample>(image: &[S], [nx, ny, nz]: [usize; 3], sigma: f64) -> Vec<S> {
    assert_eq!(
        image.len(),
        nx * ny * nz,
        "image size does not match dimensions"
    );
    let dims = [nx, ny, nz];
    let kernel = gaussian_kernel(sigma);
    // Slowest axis first, as scipy does for a C-ordered array.
    let axes: Vec<usize> = [2usize, 1, 0]
        .into_iter()
        .filter(|&a| dims[a] > 1)
        .collect();
    let (Some((&first, rest)), false) = (axes.split_first(), kernel.len() == 1) else {
        return image.to_vec();
    };
    let mut out = vec![S::narrow(0.0); image.len()];
    let Some((&last, between)) = rest.split_last() else {
        blur_axis(image, &mut out, dims, first, &kernel);
        return out;
    };
    let mut cur = vec![0.0f64; image.len()];
    blur_axis(image, &mut cur, dims, first, &kernel);
    if let Some(&middle) = between.first() {
        let mut next = vec![0.0f64; image.len()];
        blur_axis(&cur, &mut next, dims, middle, &kernel);
        cur = next;
    }
    blur_axis(&cur, &mut out, dims, last, &kernel);
    out
}

/// Sum in the order of numpy's pairwise summation (`np.sum` of a
/// contiguous `float64` array), so the kernel normalisation is bit-identical.
fn numpy_sum(a: &[f64]) -> f64 {
    const BLOCK: usize = 128;
    let n = a.len();
    if n < 8 {
        a.iter().fold(0.0, |s, &v| s + v)
    } else if n <= BLOCK {
        let mut r = [0.0f64; 8];
        r.copy_from_slice(&a[..8]);
        let mut i = 8;
        while i < n - n % 8 {
            for j in 0..8 {
                r[j] += a[i + j];
            }
            i += 8;
        }
        let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for &v in &a[i..] {
            res += v;
        }
        res
    } else {
        let mut n2 = n / 2;
        n2 -= n2 % 8;
        numpy_sum(&a[..n2]) + numpy_sum(&a[n2..])
    }
}

/// Samples below which a pass runs on the calling thread: at 256² a pass
/// takes about a tenth of a millisecond, about what waking rayon's workers
/// costs on a 2-core machine.
pub const PARALLEL_FROM: usize = 1 << 18;

/// One 1D pass along `axis` (0 = x, 1 = y, 2 = z); parallel over x-rows
/// from [`PARALLEL_FROM`] samples. The kernel is symmetric; samples are
/// combined in SciPy's order (`w₀·c + Σ_{d=r..1} w_d·(left_d + right_d)`),
/// row by row in an `f64` scratch row.
fn blur_axis<S: Sample, D: Sample>(
    src: &[S],
    dst: &mut [D],
    dims: [usize; 3],
    axis: usize,
    kernel: &[f64],
) {
    let [nx, ny, nz] = dims;
    let r = kernel.len() / 2;
    let w0 = kernel[r];
    let (extent, stride_rows) = if axis == 1 { (ny, 1) } else { (nz, ny) };
    let last = extent as isize - 1;
    let pass = |(padded, sums): &mut (Vec<f64>, Vec<f64>), (row, out): (usize, &mut [D])| {
        sums.resize(nx, 0.0);
        if axis == 0 {
            blur_row(&src[row * nx..(row + 1) * nx], sums, kernel, padded);
        } else {
            let (c, base) = if axis == 1 {
                (row % ny, row - row % ny)
            } else {
                (row / ny, row % ny)
            };
            let line = |cc: isize| {
                let srow = base + cc.clamp(0, last) as usize * stride_rows;
                &src[srow * nx..(srow + 1) * nx]
            };
            let c = c as isize;
            sums.iter_mut()
                .zip(line(c))
                .for_each(|(o, &v)| *o = v.wide() * w0);
            for d in (1..=r).rev() {
                let (lo, hi) = (line(c - d as isize), line(c + d as isize));
                let w = kernel[r - d];
                for ((o, &a), &b) in sums.iter_mut().zip(lo).zip(hi) {
                    *o += (a.wide() + b.wide()) * w;
                }
            }
        }
        out.iter_mut()
            .zip(sums.iter())
            .for_each(|(o, &v)| *o = D::narrow(v));
    };
    if dst.len() < PARALLEL_FROM {
        let mut scratch = Default::default();
        dst.chunks_mut(nx)
            .enumerate()
            .for_each(|entry| pass(&mut scratch, entry));
    } else {
        dst.par_chunks_mut(nx)
            .enumerate()
            .for_each_init(Default::default, pass);
    }
}

/// One row's pass along x: the row padded by its end samples (the clamp
/// border) into `padded` (scratch), then each tap added over the whole row
/// at once, in the order of the other axes' passes (`w₀·c`, then the taps
/// from the outermost in), so the sums are those of a per-sample loop, bit
/// for bit, in a loop the compiler vectorises.
fn blur_row<S: Sample>(row: &[S], out: &mut [f64], kernel: &[f64], padded: &mut Vec<f64>) {
    let r = kernel.len() / 2;
    let n = row.len();
    padded.clear();
    padded.extend(std::iter::repeat_n(row[0].wide(), r));
    padded.extend(row.iter().map(|v| v.wide()));
    padded.extend(std::iter::repeat_n(row[n - 1].wide(), r));
    let w0 = kernel[r];
    out.iter_mut()
        .zip(&padded[r..r + n])
        .for_each(|(o, &v)| *o = v * w0);
    for d in (1..=r).rev() {
        let w = kernel[r - d];
        let (lo, hi) = (&padded[r - d..r - d + n], &padded[r + d..r + d + n]);
        for ((o, &a), &b) in out.iter_mut().zip(lo).zip(hi) {
            *o += (a + b) * w;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_matches_scipy_radius_and_sums_to_one() {
        let k = gaussian_kernel(1.5);
        assert_eq!(k.len(), 13); // radius int(4*1.5 + 0.5) = 6
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert_eq!(gaussian_kernel(0.0), vec![1.0]);
    }

    #[test]
    fn constant_is_preserved_and_mass_spreads() {
        let img = vec![0.5f32; 7 * 5 * 3];
        let out = gaussian_blur_3d(&img, 7, 5, 3, 1.0);
        assert!(out.iter().all(|v| (v - 0.5).abs() < 1e-6));
        let mut imp = vec![0.0f32; 21 * 21];
        imp[10 * 21 + 10] = 1.0;
        let out = gaussian_blur_2d(&imp, 21, 21, 1.0);
        let s: f32 = out.iter().sum();
        assert!((s - 1.0).abs() < 1e-5);
        // symmetric in x and y
        assert!((out[10 * 21 + 12] - out[12 * 21 + 10]).abs() < 1e-7);
        assert!((out[10 * 21 + 8] - out[10 * 21 + 12]).abs() < 1e-7);
    }

    /// The padded, tap-by-tap pass along x gives the per-sample clamped sum
    /// bit for bit, on rows shorter and longer than the kernel.
    #[test]
    fn an_f32_image_is_blurred_as_its_f64_copy_to_the_bit() {
        for (dims, sigma) in [
            ([9, 1, 1], 1.0),
            ([13, 7, 1], 0.8),
            ([6, 5, 4], 1.5),
            ([1, 1, 8], 2.0),
        ] {
            let n = dims.iter().product::<usize>();
            let image: Vec<f32> = (0..n).map(|i| ((i * 7919) % 101) as f32 / 17.0).collect();
            let wide: Vec<f64> = image.iter().map(|&v| v as f64).collect();
            let [nx, ny, nz] = dims;
            let expected: Vec<u32> = gaussian_blur_3d_f64(&wide, nx, ny, nz, sigma)
                .into_iter()
                .map(|v| (v as f32).to_bits())
                .collect();
            let got: Vec<u32> = gaussian_blur_3d(&image, nx, ny, nz, sigma)
                .into_iter()
                .map(f32::to_bits)
                .collect();
            assert_eq!(got, expected, "{dims:?}");
        }
    }

    #[test]
    fn the_row_pass_is_the_clamped_sum_bit_for_bit() {
        let kernel = gaussian_kernel(1.3);
        let r = kernel.len() / 2;
        for n in [1, 2, 5, 9, 40] {
            let row: Vec<f64> = (0..n).map(|i| ((i * 7919) % 97) as f64 / 13.0).collect();
            let mut out = vec![0.0; n];
            blur_row(&row, &mut out, &kernel, &mut Vec::new());
            let at = |j: isize| row[j.clamp(0, n as isize - 1) as usize];
            for (i, &o) in out.iter().enumerate() {
                let i = i as isize;
                let mut acc = at(i) * kernel[r];
                for d in (1..=r).rev() {
                    acc += (at(i - d as isize) + at(i + d as isize)) * kernel[r - d];
                }
                assert_eq!(o.to_bits(), acc.to_bits(), "row of {n}, sample {i}");
            }
        }
    }

    #[test]
    fn axis_3d_matches_2d_slices_for_x_y() {
        // A volume whose slices differ only by a constant: blurring along z of
        // a z-constant volume leaves 2D blur per slice.
        let (nx, ny, nz) = (9, 6, 4);
        let slice: Vec<f32> = (0..nx * ny)
            .map(|i| ((i * 37) % 11) as f32 / 10.0)
            .collect();
        let vol: Vec<f32> = (0..nz).flat_map(|_| slice.iter().copied()).collect();
        let b2 = gaussian_blur_2d(&slice, nx, ny, 1.2);
        let b3 = gaussian_blur_3d(&vol, nx, ny, nz, 1.2);
        for z in 0..nz {
            for i in 0..nx * ny {
                assert!((b3[z * nx * ny + i] - b2[i]).abs() < 1e-6);
            }
        }
    }
}
