//! Local mesh operations, each generic over dimension unless its name says otherwise.
//!
//! Every operation either succeeds, leaving a valid complex, or returns a
//! [`Rejection`](crate::complex::Rejection) and changes nothing.

mod collapse;
mod flip2d;
mod relocate;
mod smooth;
mod split;

pub use collapse::CollapseMode;
pub use relocate::MoveOutcome;
