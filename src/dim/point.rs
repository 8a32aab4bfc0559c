use nalgebra::SVector;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Index, IndexMut, Mul, Sub, SubAssign};

/// The vector operations the generic mesh code needs from a point type.
pub trait Point:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
    + SubAssign
    + Index<usize, Output = f64>
    + IndexMut<usize>
{
    /// The origin / zero vector.
    fn zero() -> Self;
    /// Euclidean inner product.
    fn dot(&self, other: &Self) -> f64;
    /// Euclidean length.
    fn length(&self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Whether every coordinate is finite.
    fn is_finite(&self) -> bool;
}

impl<const N: usize> Point for SVector<f64, N> {
    fn zero() -> Self {
        SVector::zeros()
    }
    fn dot(&self, other: &Self) -> f64 {
        nalgebra::Matrix::dot(self, other)
    }
    fn is_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}
