//! Stretching a complex onto a slightly different domain box.

use super::build::BuildError;
use super::Complex;
use crate::dim::{Dim, Point};

/// Layer `complex`: moving the whole complex onto another box.
impl<K: Dim> Complex<K> {
    /// Maps the complex from its box `[min, max]` onto `[min, new_max]` by
    /// scaling each axis about `min`, so that a mesh built on a grid of
    /// another extent (a downsampled image whose odd side was rounded up)
    /// covers the new box exactly: positions on the old upper faces land
    /// exactly on the new ones, and the vertex classes are recomputed. An
    /// axis whose extent does not change keeps its coordinates bit for bit.
    ///
    /// Scaling an axis preserves orientation in exact arithmetic, but
    /// rounding may not for a nearly flat cell: the exact orientation of
    /// every cell is checked before anything changes, and a cell that would
    /// not stay positive is an error ([`BuildError::Degenerate`], the complex
    /// untouched). The stretched complex has a new identity, as a clone
    /// does, so no record kept against the old one is read against it.
    pub fn stretch_to(&mut self, new_max: K::Point) -> Result<(), BuildError> {
        let (min, max) = (self.domain_min, self.domain_max);
        if !(0..K::N).all(|a| new_max[a].is_finite() && new_max[a] > min[a]) {
            return Err(BuildError::BadDomain);
        }
        let map = |x: f64, a: usize| -> f64 {
            if new_max[a] == max[a] || x == min[a] {
                x
            } else if x == max[a] {
                new_max[a]
            } else {
                min[a] + (x - min[a]) * ((new_max[a] - min[a]) / (max[a] - min[a]))
            }
        };
        let positions: Vec<K::Point> = self
            .positions
            .iter()
            .map(|p| {
                let mut q = *p;
                for a in 0..K::N {
                    q[a] = map(p[a], a);
                }
                q
            })
            .collect();
        for c in self.cell_ids() {
            let mut p = [K::Point::zero(); 4];
            for (o, v) in p.iter_mut().zip(self.cell(c)) {
                *o = positions[v.index()];
            }
            if K::orient(&p[..K::NV]) <= 0.0 {
                return Err(BuildError::Degenerate(c.index()));
            }
        }
        self.positions = positions;
        self.domain_max = new_max;
        // Every vertex may have moved without a clock: records kept
        // against this complex (the improvement memo, refused collapses)
        // must not be read against the stretched one.
        self.book.renew_identity();
        self.reclassify_all();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{D2, D3};
    use nalgebra::{Vector2, Vector3};

    #[test]
    fn a_stretched_box_mesh_covers_the_new_box_and_validates() {
        let mut c = Complex::<D3>::cuboid([8.0, 6.0, 4.0], 2.0).unwrap();
        let before = c.to_arrays();
        let identity = c.identity();
        c.stretch_to(Vector3::new(7.0, 6.0, 3.5)).unwrap();
        assert_ne!(c.identity(), identity, "a stretched complex is another one");
        assert!(c.validate().is_empty(), "{:?}", c.validate());
        assert_eq!(c.domain().1, Vector3::new(7.0, 6.0, 3.5));
        assert!((c.domain_measure() - 7.0 * 6.0 * 3.5).abs() < 1e-9);
        let after = c.to_arrays();
        let on_top = after.points.iter().filter(|p| p[0] == 7.0).count();
        assert_eq!(on_top, before.points.iter().filter(|p| p[0] == 8.0).count());
        // The unchanged axis keeps its coordinates bit for bit.
        assert!(before
            .points
            .iter()
            .zip(&after.points)
            .all(|(a, b)| a[1] == b[1]));
    }

    #[test]
    fn stretching_in_2d_and_to_a_bad_box() {
        let mut c = Complex::<D2>::rectangle(10.0, 10.0, 2.5).unwrap();
        c.stretch_to(Vector2::new(9.0, 11.0)).unwrap();
        assert!(c.validate().is_empty());
        assert_eq!(
            c.stretch_to(Vector2::new(0.0, 11.0)),
            Err(BuildError::BadDomain)
        );
    }
}
