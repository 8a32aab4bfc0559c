//! A user-interaction force after Kass's volcano: a point placed by the user
//! repels (or, with negative strength, attracts) the interface near it.
//!
//! Every interface vertex at distance `r` from the centre `c` feels
//! `s · (x − c)/r · exp(−r²/(2ρ²))`: strength `s` at the centre, fading over
//! the radius `ρ`. Move, strengthen or switch it off mid-run through
//! [`Segmentation::force_mut`](crate::segment::Segmentation::force_mut).

use crate::complex::Complex;
use crate::complex::VertexKind;
use crate::dim::Point;
use crate::segment::model::{ForceTerm, IterationState};
use crate::segment::raster::Raster;

/// A repelling (`strength > 0`) or attracting (`strength < 0`) point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volcano<P> {
    /// The centre, in pixel units.
    pub centre: P,
    /// The strength `s`, in units of the reference magnitude 1 (a pixel at a
    /// phase mean in eq. 6); 0 switches the volcano off.
    pub strength: f64,
    /// The radius `ρ` of influence, in pixels.
    pub radius: f64,
}

impl<P: Point> Volcano<P> {
    /// A volcano at `centre` with the given strength and radius.
    pub fn new(centre: P, strength: f64, radius: f64) -> Self {
        Volcano {
            centre,
            strength,
            radius,
        }
    }

    /// The force at `x`.
    pub fn force_at(&self, x: P) -> P {
        let d = x - self.centre;
        let r = d.length();
        if r <= 0.0 || self.strength == 0.0 {
            return P::zero();
        }
        let fade = (-(r * r) / (2.0 * self.radius * self.radius)).exp();
        d * (self.strength * fade / r)
    }
}

impl<K: Raster> ForceTerm<K> for Volcano<K::Point> {
    fn name(&self) -> &str {
        "volcano"
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
            out[v.index()] += self.force_at(complex.position(v));
        }
    }
}
