use super::Dim;
use crate::complex::{CellId, VertexId};
use nalgebra::Vector2;

/// Two dimensions: triangles over an image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct D2;

fn coord(p: &Vector2<f64>) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

impl Dim for D2 {
    const N: usize = 2;
    type Point = Vector2<f64>;
    type Cell = [VertexId; 3];
    type Neighbours = [Option<CellId>; 3];

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
    /// Smallest angle over 60°: the max-min-angle criterion of the 2D DSC.
    fn quality(p: &[Self::Point]) -> f64 {
        if Self::orient(p) <= 0.0 {
            return 0.0;
        }
        // The smallest angle faces the shortest edge and is at most 60°, so
        // sin θ = 2·area / (product of the two longer edges) determines it
        // with one asin instead of three atan2.
        let mut l2 = [
            (p[1] - p[2]).norm_squared(),
            (p[2] - p[0]).norm_squared(),
            (p[0] - p[1]).norm_squared(),
        ];
        l2.sort_unstable_by(f64::total_cmp);
        let sin = (2.0 * Self::signed_measure(p) / (l2[1] * l2[2]).sqrt()).clamp(0.0, 1.0);
        (sin.asin() / (std::f64::consts::PI / 3.0)).clamp(0.0, 1.0)
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
    fn quality_is_the_smallest_angle_over_sixty_degrees() {
        let tri = [
            Vector2::new(0.0, 0.0),
            Vector2::new(4.0, 0.0),
            Vector2::new(1.0, 0.5),
        ];
        let by_angles = angles(&tri).iter().copied().fold(f64::INFINITY, f64::min)
            / (std::f64::consts::PI / 3.0);
        assert!((D2::quality(&tri) - by_angles).abs() < 1e-12);
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
