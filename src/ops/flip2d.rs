//! 2D edge flips towards the Delaunay (max-min-angle) triangulation.
//!
//! ```text
//!      a                 a
//!     /|\               / \
//!    b | d     ==>     b---d     (only for edges off the interface, in a convex quad)
//!     \|/               \ /
//!      c                 c
//! ```

use crate::complex::{CellId, Complex, Label, Rejection, VertexId};
use crate::dim::D2;

fn coord(p: nalgebra::Vector2<f64>) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

/// Layer `ops`: 2D edge flips.
impl Complex<D2> {
    /// Flips the edge opposite local vertex `i` of cell `c` if it is off the
    /// interface and not locally Delaunay (exact incircle test).
    pub fn flip_if_better(&mut self, c: CellId, i: usize) -> Result<bool, Rejection> {
        if !self.is_alive(c) {
            return Err(Rejection::Stale);
        }
        let Some(nb) = self.neighbours(c)[i] else {
            return Ok(false);
        };
        if self.label(nb) != self.label(c) {
            return Ok(false);
        }
        let cell = self.cell(c);
        let a = cell[i];
        let (b, d) = (cell[(i + 1) % 3], cell[(i + 2) % 3]);
        let far: VertexId = *self
            .cell(nb)
            .iter()
            .find(|&&w| w != b && w != d)
            .expect("neighbour has a third vertex");
        let inside = robust::incircle(
            coord(self.position(a)),
            coord(self.position(b)),
            coord(self.position(d)),
            coord(self.position(far)),
        );
        if inside <= 0.0 {
            return Ok(false);
        }
        let label: Label = self.label(c);
        let new = [([a, b, far], label), ([a, far, d], label)];
        match self.replace_cells(&[c, nb], &new) {
            Ok(()) => Ok(true),
            Err(Rejection::WouldInvert) => Ok(false),
            Err(e) => Err(e),
        }
    }
}
