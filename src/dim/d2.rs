use super::{Dim, QualityDefaults};
use crate::ids::{CellId, VertexId};
use nalgebra::Vector2;

/// Two dimensions: triangles over an image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D2;

fn coord(p: &Vector2<f64>) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

const SIN_60: f64 = 0.866_025_403_784_438_6;

impl D2 {
    /// The quality of a triangle whose smallest angle is `degrees` (≤ 60).
    pub fn quality_of_min_angle(degrees: f64) -> f64 {
        degrees.to_radians().sin() / SIN_60
    }
    /// The smallest angle, in degrees, of a triangle of quality `q`.
    pub fn min_angle_of_quality(q: f64) -> f64 {
        (q * SIN_60).clamp(0.0, 1.0).asin().to_degrees()
    }
}

impl Dim for D2 {
    const N: usize = 2;
    const STAR_IS_FAN: bool = true;
    const EDGE_JUNCTIONS: bool = false;
    const SAMPLES: &'static str = "pixels";
    const SMALLEST_GRID: &'static str = "2×2";
    const SPLITS_UNCOLLAPSIBLE: bool = false;
    const REORDERS_SPATIALLY: bool = false;
    type Point = Vector2<f64>;
    type Cell = [VertexId; 3];
    type Neighbours = [Option<CellId>; 3];

    /// Degenerate below a 2° smallest angle, improved below 10°.
    fn quality_defaults() -> QualityDefaults {
        QualityDefaults {
            degenerate: D2::quality_of_min_angle(2.0),
            minimum: D2::quality_of_min_angle(10.0),
            straight_angle_deg: 10.0,
        }
    }
    fn cell(v: &[VertexId]) -> Self::Cell {
        [v[0], v[1], v[2]]
    }
    fn no_neighbours() -> Self::Neighbours {
        [None; 3]
    }
    fn orient(p: &[Self::Point]) -> f64 {
        robust::orient2d(coord(&p[0]), coord(&p[1]), coord(&p[2]))
    }
    fn signed_measure(p: &[Self::Point]) -> f64 {
        let a = p[1] - p[0];
        let b = p[2] - p[0];
        0.5 * (a.x * b.y - a.y * b.x)
    }
    /// sin(smallest angle) / sin(60°): monotone in the smallest angle (the
    /// max-min-angle criterion of the 2D DSC), 1 for the equilateral triangle,
    /// and cheap: the smallest angle faces the shortest edge, so its sine is
    /// 2·area / (product of the two longer edges); no trigonometry at all.
    fn quality(p: &[Self::Point]) -> f64 {
        let area = Self::signed_measure(p);
        if area <= 0.0 {
            return 0.0;
        }
        let l2 = [
            (p[1] - p[2]).norm_squared(),
            (p[2] - p[0]).norm_squared(),
            (p[0] - p[1]).norm_squared(),
        ];
        let shortest = l2[0].min(l2[1]).min(l2[2]);
        let sin = 2.0 * area * (shortest / (l2[0] * l2[1] * l2[2])).sqrt();
        (sin / SIN_60).clamp(0.0, 1.0)
    }
    /// Compares the squares, `4·area²·shortest` against
    /// `(q_min·sin 60°)²·l0²·l1²·l2²`, outside a relative band of 1e-9 (far
    /// wider than the rounding of either side); inside it, and for NaN,
    /// [`quality`](Dim::quality) decides, so the answer is always exactly
    /// `quality(p) >= q_min`. Smoothing asks this of every cell it looks at.
    #[inline]
    fn quality_at_least(p: &[Self::Point], q_min: f64) -> bool {
        if q_min > 1.0 {
            return false;
        }
        let area = Self::signed_measure(p);
        if area <= 0.0 {
            return 0.0 >= q_min;
        }
        let l2 = [
            (p[1] - p[2]).norm_squared(),
            (p[2] - p[0]).norm_squared(),
            (p[0] - p[1]).norm_squared(),
        ];
        let shortest = l2[0].min(l2[1]).min(l2[2]);
        let lhs = 4.0 * area * area * shortest;
        let t = q_min * SIN_60;
        let rhs = t * t * (l2[0] * l2[1] * l2[2]);
        if lhs >= rhs * (1.0 + 1e-9) {
            true
        } else if lhs <= rhs * (1.0 - 1e-9) {
            q_min <= 0.0
        } else {
            Self::quality(p) >= q_min
        }
    }
    fn regular_measure(l: f64) -> f64 {
        3f64.sqrt() / 4.0 * l * l
    }
    fn facet_normal(p: &[Self::Point], opposite: usize) -> Self::Point {
        let a = p[(opposite + 1) % 3];
        let b = p[(opposite + 2) % 3];
        let d = b - a;
        let mut n = Vector2::new(d.y, -d.x);
        if n.dot(&(p[opposite] - a)) > 0.0 {
            n = -n;
        }
        n.normalize()
    }
    fn facet_measure(p: &[Self::Point], opposite: usize) -> f64 {
        (p[(opposite + 2) % 3] - p[(opposite + 1) % 3]).norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Interior angles of a triangle, in radians.
    pub fn angles(p: &[Vector2<f64>]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (i, angle) in out.iter_mut().enumerate() {
            let a = p[(i + 1) % 3] - p[i];
            let b = p[(i + 2) % 3] - p[i];
            let cross = a.x * b.y - a.y * b.x;
            *angle = cross.abs().atan2(a.dot(&b));
        }
        out
    }

    #[test]
    fn quality_at_least_agrees_with_quality() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20_000 {
            let tri: [Vector2<f64>; 3] =
                std::array::from_fn(|_| Vector2::new(rng.random::<f64>(), rng.random::<f64>()));
            let q = D2::quality(&tri);
            // thresholds away from q, at q itself and one ulp either side
            for t in [0.0, 0.3, 0.8, 1.0, 1.5, q, q.next_up(), q.next_down()] {
                assert_eq!(D2::quality_at_least(&tri, t), q >= t, "{tri:?} {t}");
            }
        }
    }

    #[test]
    fn quality_measures_the_smallest_angle() {
        let tri = [
            Vector2::new(0.0, 0.0),
            Vector2::new(4.0, 0.0),
            Vector2::new(1.0, 0.5),
        ];
        let smallest = angles(&tri)
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .to_degrees();
        assert!((D2::min_angle_of_quality(D2::quality(&tri)) - smallest).abs() < 1e-9);
        assert!((D2::quality_of_min_angle(smallest) - D2::quality(&tri)).abs() < 1e-12);
        let equilateral = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.5, 3f64.sqrt() / 2.0),
        ];
        assert!((D2::quality(&equilateral) - 1.0).abs() < 1e-12);
        let inverted = [tri[0], tri[2], tri[1]];
        assert_eq!(D2::quality(&inverted), 0.0);
    }
}
