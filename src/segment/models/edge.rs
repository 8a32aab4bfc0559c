//! The classical snake external force (Kass et al.): the interface is pulled
//! towards large gradients of the smoothed image.
//!
//! With the edge potential `P = |∇(G_σ ∗ I)|²` (normalised to a largest value
//! of 1), the force is `F = w · ∇P / max|∇P|`: it points uphill on `P`, i.e.
//! towards the nearest edge, within a capture range of about `2σ`. Written
//! once for any dimension (central differences along every axis of extent
//! > 1, interpolation by [`Raster::sample`]).

use crate::complex::Complex;
use crate::complex::VertexKind;
use crate::dim::Point;
use crate::phantom::blur::gaussian_blur_3d;
use crate::segment::image::ImageView;
use crate::segment::model::{ForceTerm, IterationState};
use crate::segment::raster::Raster;
use std::sync::Arc;

/// The edge potential `P = |∇(G_σ ∗ I)|²` of an image (largest value 1) and
/// its gradient `∇P` (largest length 1), sampled on the pixel grid.
#[derive(Clone, Debug)]
pub struct EdgeMap {
    dims: [usize; 3],
    /// `P` per pixel.
    potential: Vec<f32>,
    /// `∂P/∂x_axis` per pixel, for the axes `0..3`.
    gradient: [Vec<f32>; 3],
}

/// Central (one-sided at the border) difference of `f` along `axis`.
fn derivative(f: &[f32], dims: [usize; 3], axis: usize) -> Vec<f32> {
    let n = dims[axis];
    let stride: usize = dims[..axis].iter().product();
    let mut out = vec![0.0f32; f.len()];
    if n < 2 {
        return out;
    }
    for (i, o) in out.iter_mut().enumerate() {
        let c = (i / stride) % n;
        let (lo, hi) = (c.saturating_sub(1), (c + 1).min(n - 1));
        let a = f[i - (c - lo) * stride];
        let b = f[i + (hi - c) * stride];
        *o = (b - a) / (hi - lo) as f32;
    }
    out
}

impl EdgeMap {
    /// Smooths `image` with a Gaussian of standard deviation `sigma` pixels
    /// ([`gaussian_blur_3d`]) and computes the potential and its gradient.
    pub fn new(image: &ImageView<'_>, sigma: f64) -> Self {
        let d = image.dims;
        let smooth = gaussian_blur_3d(image.data, d[0], d[1], d[2], sigma);
        let mut potential = vec![0.0f32; smooth.len()];
        for axis in 0..3 {
            let g = derivative(&smooth, d, axis);
            for (p, g) in potential.iter_mut().zip(&g) {
                *p += g * g;
            }
        }
        let pmax = potential.iter().copied().fold(0.0f32, f32::max);
        if pmax > 0.0 {
            potential.iter_mut().for_each(|p| *p /= pmax);
        }
        let mut gradient = [0, 1, 2].map(|axis| derivative(&potential, d, axis));
        let gmax = (0..potential.len())
            .map(|i| gradient.iter().map(|g| g[i] * g[i]).sum::<f32>())
            .fold(0.0f32, f32::max)
            .sqrt();
        if gmax > 0.0 {
            for g in &mut gradient {
                g.iter_mut().for_each(|v| *v /= gmax);
            }
        }
        EdgeMap {
            dims: d,
            potential,
            gradient,
        }
    }

    /// The potential `P ∈ [0, 1]` interpolated at `p`.
    pub fn potential<K: Raster>(&self, p: K::Point) -> f64 {
        K::sample(&self.view(&self.potential), p)
    }

    /// The normalised gradient `∇P / max|∇P|` interpolated at `p`.
    pub fn gradient<K: Raster>(&self, p: K::Point) -> K::Point {
        let mut g = K::Point::zero();
        for axis in 0..K::N {
            g[axis] = K::sample(&self.view(&self.gradient[axis]), p);
        }
        g
    }

    /// The potential per pixel, row-major like the image.
    pub fn potential_image(&self) -> &[f32] {
        &self.potential
    }

    fn view<'s>(&self, data: &'s [f32]) -> ImageView<'s> {
        ImageView::new_3d(self.dims, data).expect("the potential has the image's size")
    }
}

/// The snake's edge force `w · ∇P / max|∇P|` on every interface vertex (see
/// the [module docs](self)). An external term with the default reference
/// magnitude 1: where `|F| = 1` a vertex moves a full step.
#[derive(Clone, Debug)]
pub struct EdgeAttraction {
    /// The edge map (shareable with a [`Balloon`](super::Balloon)'s edge stop).
    pub map: Arc<EdgeMap>,
    /// The weight `w`.
    pub weight: f64,
}

impl EdgeAttraction {
    /// The edge force of `map` with weight `weight`.
    pub fn new(map: Arc<EdgeMap>, weight: f64) -> Self {
        EdgeAttraction { map, weight }
    }
}

impl<K: Raster> ForceTerm<K> for EdgeAttraction {
    fn name(&self) -> &str {
        "edge attraction"
    }

    fn add_forces(
        &mut self,
        complex: &Complex<K>,
        _state: &IterationState<'_, '_>,
        out: &mut [K::Point],
    ) {
        for v in complex.vertex_ids() {
            if complex.class(v).kind == VertexKind::Interior {
                continue;
            }
            let g = self.map.gradient::<K>(complex.position(v));
            out[v.index()] += g * self.weight;
        }
    }
}
