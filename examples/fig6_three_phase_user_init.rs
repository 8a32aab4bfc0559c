//! Fig. 6 of the paper: three phases from a user initialisation, no label flips.
//! Writes its panels into `paper/figures/`.
//!
//! ```sh
//! cargo run --release --example fig6_three_phase_user_init
//! ```

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    common::reproduce(dsc_seg::figures::Figure::Fig6).map(|_| ())
}
