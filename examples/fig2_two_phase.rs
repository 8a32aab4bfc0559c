//! Fig. 2 of the paper: two-phase segmentation with crossings and holes.
//! Writes its panels into `paper/figures/`.
//!
//! ```sh
//! cargo run --release --example fig2_two_phase
//! ```

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    common::reproduce(dsc_seg::figures::Figure::Fig2).map(|_| ())
}
