//! Fig. 5 of the paper: the effect of the edge length L (10 against 15).
//! Writes its panels into `paper/figures/`.
//!
//! ```sh
//! cargo run --release --example fig5_edge_length
//! ```

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    common::reproduce(dsc_seg::figures::Figure::Fig5).map(|_| ())
}
