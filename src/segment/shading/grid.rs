//! The grid of samples the trend check visits, the blocks it is cut into
//! and the quadratic monomials of a position on it.

use super::{BLOCKS, MAX_FIT_SAMPLES};

/// The grid of samples the check visits, and positions on it.
pub(super) struct Grid {
    pub(super) dims: [usize; 3],
    /// The step between visited samples along every axis.
    pub(super) stride: usize,
    /// Per axis, the index of the first visited sample.
    offset: [usize; 3],
    /// Per axis, how many samples are visited along it.
    pub(super) extent: [usize; 3],
    /// Blocks along every axis longer than one sample: as many on each,
    /// at most [`BLOCKS`] in all.
    blocks_per_axis: usize,
    /// Per axis longer than one sample (in order), each index's coordinate
    /// scaled to `[-1, 1]` over the image.
    scaled: Vec<(usize, Vec<f64>)>,
}

impl Grid {
    /// The grid over an image of `dims`: every sample, or every `stride`-th
    /// along each axis so that at most [`MAX_FIT_SAMPLES`] are visited.
    pub(super) fn new(dims: [usize; 3]) -> Self {
        let visited = |s: usize| dims.iter().map(|n| n.div_ceil(s)).product::<usize>();
        let mut stride = 1;
        while visited(stride) > MAX_FIT_SAMPLES {
            stride += 1;
        }
        let scaled: Vec<(usize, Vec<f64>)> = (0..3)
            .filter(|&a| dims[a] > 1)
            .map(|a| {
                let n = dims[a];
                let scale = (0..n)
                    .map(|c| 2.0 * c as f64 / (n - 1) as f64 - 1.0)
                    .collect();
                (a, scale)
            })
            .collect();
        let offset = dims.map(|n| (n - 1) % stride / 2);
        let extent = [0, 1, 2].map(|a| (dims[a] - offset[a]).div_ceil(stride));
        let axes = scaled.len() as u32;
        let blocks_per_axis = (1..=BLOCKS)
            .take_while(|b| b.pow(axes) <= BLOCKS)
            .last()
            .unwrap_or(1);
        Grid {
            dims,
            stride,
            offset,
            extent,
            blocks_per_axis,
            scaled,
        }
    }

    /// How many points the grid visits.
    pub(super) fn count(&self) -> usize {
        self.extent.iter().product()
    }

    /// The sample indices (x, y, z) of the grid point `g` (grid indices).
    pub(super) fn at(&self, g: [usize; 3]) -> [usize; 3] {
        [0, 1, 2].map(|a| self.offset[a] + g[a] * self.stride)
    }

    /// Which of the blocks along `axis` the grid index `g` falls in.
    pub(super) fn block(&self, axis: usize, g: usize) -> usize {
        g * self.blocks_per_axis / self.extent[axis]
    }

    /// How many axes are longer than one sample.
    pub(super) fn axes(&self) -> usize {
        self.scaled.len()
    }

    /// The quadratic monomials of position at `at` (1, the coordinates,
    /// their products and squares), each coordinate scaled to `[-1, 1]`
    /// over the image; axes one sample long are left out. `P` is their
    /// number, `1 + d + d(d + 1)/2` for the `d` [`Grid::axes`]: 6 in 2D,
    /// 10 in 3D.
    #[inline]
    pub(super) fn basis<const P: usize>(&self, at: [u32; 3]) -> [f64; P] {
        let mut u = [0.0; 3];
        for (k, (a, scale)) in self.scaled.iter().enumerate() {
            u[k] = scale[at[*a] as usize];
        }
        let axes = self.scaled.len();
        let mut out = [0.0; P];
        out[0] = 1.0;
        out[1..=axes].copy_from_slice(&u[..axes]);
        let mut k = axes + 1;
        for a in 0..axes {
            for b in a..axes {
                out[k] = u[a] * u[b];
                k += 1;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_image_is_taken_on_a_coarser_grid() {
        let grid = Grid::new([1024, 1024, 1]);
        assert_eq!(grid.stride, 4);
        assert!(grid.count() <= MAX_FIT_SAMPLES);
        assert_eq!(grid.at([0, 0, 0]), [1, 1, 0], "centred: 1023 % 4 / 2");
        let grid = Grid::new([100, 100, 100]);
        assert!(grid.count() <= MAX_FIT_SAMPLES && grid.stride == 3);
        assert_eq!(grid.extent, [34, 34, 34]);
    }

    #[test]
    fn blocks_cut_every_axis_into_equal_parts() {
        let grid = Grid::new([64, 40, 1]);
        assert_eq!(grid.blocks_per_axis, 8);
        assert_eq!(grid.block(0, 0), 0);
        assert_eq!(grid.block(0, 63), 7);
        assert_eq!(grid.block(1, 39), 7);
        assert_eq!(grid.block(2, 0), 0);
        let grid = Grid::new([48, 48, 48]);
        assert_eq!(grid.blocks_per_axis, 4);
        assert_eq!(grid.block(2, grid.extent[2] - 1), 3);
    }
}
