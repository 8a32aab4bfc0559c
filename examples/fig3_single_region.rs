//! Fig. 3 of the paper: one region grown from a disk, no label flips.
//! Writes its panels into `paper/figures/`.
//!
//! ```sh
//! cargo run --release --example fig3_single_region
//! ```

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    common::reproduce(dsc_seg::figures::Figure::Fig3).map(|_| ())
}
