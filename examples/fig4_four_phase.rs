//! Fig. 4 of the paper: four phases with triple junctions.
//! Writes its panels into `paper/figures/`.
//!
//! ```sh
//! cargo run --release --example fig4_four_phase
//! ```

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    common::reproduce(dsc_seg::figures::Figure::Fig4).map(|_| ())
}
