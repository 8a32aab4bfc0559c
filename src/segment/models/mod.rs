//! Force terms, label rules and initialisations written against
//! [`crate::segment::model`].
//!
//! - [`paper`]: the paper's evolution (region force, rigidity, elasticity,
//!   cell and component flips, initialisation from the parameters);
//! - [`band_flips`]: layers of an intermediate phase along blurred edges
//!   given back to the phases on their sides (3D, three or more phases);
//! - [`balloon`]: a pressure force inflating (or deflating) a phase, with an
//!   optional edge stop (Cohen's balloons);
//! - [`edge`]: the classical snake external force pulling the interface to
//!   large gradients of the smoothed image (Kass et al.);
//! - [`volcano`]: a user-placed point that repels or attracts the nearby
//!   interface (Kass's volcano).

pub mod balloon;
pub mod band_flips;
pub mod edge;
pub mod paper;
pub mod volcano;

pub use balloon::Balloon;
pub use band_flips::BandFlips;
pub use edge::{EdgeAttraction, EdgeMap};
pub use paper::{
    CellFlips, ComponentFlips, Elasticity, GivenMesh, PaperField, PaperTerms, ParamsInit,
    RegionForce, Rigidity,
};
pub use volcano::Volcano;
