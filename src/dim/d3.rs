use super::{Dim, QualityDefaults};
use crate::ids::{CellId, VertexId};
use nalgebra::Vector3;

/// Three dimensions: tetrahedra over a volume.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D3;

fn coord(p: &Vector3<f64>) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

impl Dim for D3 {
    const N: usize = 3;
    const STAR_IS_FAN: bool = false;
    const EDGE_JUNCTIONS: bool = true;
    const SAMPLES: &'static str = "voxels";
    const SMALLEST_GRID: &'static str = "2×2×2";
    const SPLITS_UNCOLLAPSIBLE: bool = true;
    const REORDERS_SPATIALLY: bool = true;
    type Point = Vector3<f64>;
    type Cell = [VertexId; 4];
    type Neighbours = [Option<CellId>; 4];

    /// Interface faces are flat when adjacent normals satisfy |n1·n2| ≥ 0.995.
    fn quality_defaults() -> QualityDefaults {
        QualityDefaults {
            degenerate: 0.02,
            minimum: 0.3,
            straight_angle_deg: 0.995f64.acos().to_degrees(),
        }
    }
    fn cell(v: &[VertexId]) -> Self::Cell {
        [v[0], v[1], v[2], v[3]]
    }
    fn no_neighbours() -> Self::Neighbours {
        [None; 4]
    }
    /// `robust::orient3d` is positive when `d` lies below the plane of `a, b, c`;
    /// we negate it so that positive means `det[b-a, c-a, d-a] > 0`, like 2D.
    fn orient(p: &[Self::Point]) -> f64 {
        -robust::orient3d(coord(&p[0]), coord(&p[1]), coord(&p[2]), coord(&p[3]))
    }
    fn signed_measure(p: &[Self::Point]) -> f64 {
        (p[1] - p[0]).cross(&(p[2] - p[0])).dot(&(p[3] - p[0])) / 6.0
    }
    /// q = 6·sqrt(2)·V / l_rms³, the DSC's tet quality (1 for the regular tet).
    fn quality(p: &[Self::Point]) -> f64 {
        if Self::orient(p) <= 0.0 {
            return 0.0;
        }
        Self::quality_oriented(p)
    }
    /// The quality formula alone: the exact orientation test of
    /// [`quality`](Dim::quality) costs about as much as the formula, and
    /// most qualities asked for are of the complex's own tets. On any tet it
    /// is at least [`quality`](Dim::quality) (equal where the exact test
    /// finds the tet positive; in `[0, 1]`, and 0 rather than NaN for four
    /// coincident corners): edge removal's programme relies on it.
    #[inline]
    fn quality_oriented(p: &[Self::Point]) -> f64 {
        let mut sum_sq = 0.0;
        for i in 0..4 {
            for j in i + 1..4 {
                sum_sq += (p[i] - p[j]).norm_squared();
            }
        }
        let l_rms = (sum_sq / 6.0).sqrt();
        let q = 6.0 * 2f64.sqrt() * Self::signed_measure(p) / (l_rms * l_rms * l_rms);
        // (0/0, four coincident corners, gives 0: `clamp` would keep NaN)
        if q.is_nan() {
            0.0
        } else {
            q.clamp(0.0, 1.0)
        }
    }
    #[inline]
    fn quality_oriented_at_least(p: &[Self::Point], q_min: f64) -> bool {
        Self::quality_oriented(p) >= q_min
    }
    fn regular_measure(l: f64) -> f64 {
        2f64.sqrt() / 12.0 * l * l * l
    }
    fn facet_normal(p: &[Self::Point], opposite: usize) -> Self::Point {
        let (a, b, c) = facet_corners(p, opposite);
        let mut n = (b - a).cross(&(c - a));
        if n.dot(&(p[opposite] - a)) > 0.0 {
            n = -n;
        }
        n.normalize()
    }
    fn facet_measure(p: &[Self::Point], opposite: usize) -> f64 {
        let (a, b, c) = facet_corners(p, opposite);
        0.5 * (b - a).cross(&(c - a)).norm()
    }
}

fn facet_corners(
    p: &[Vector3<f64>],
    opposite: usize,
) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let mut it = (0..4).filter(|&i| i != opposite).map(|i| p[i]);
    (it.next().unwrap(), it.next().unwrap(), it.next().unwrap())
}
