//! Fig. 2's checkerboard under the two-phase length weight `w`: for each
//! weight, at the test suite's size (128²) and the figure's (256²), the
//! crossings left unresolved (two-phase vertices where one phase touches
//! itself at a point), the pieces per phase against the truth's
//! (4-connected) and the mean Dice. The suite's Fig. 2 test asks for no
//! crossing at 128².
//!
//! `cargo run --release --example fig2_length_weight`

use dsc_seg::figures::{self, pixel_components, Figure, FAST_SIZE, FULL_SIZE};

/// The weights measured (the 2D two-phase default is 1.6).
const WEIGHTS: [f64; 6] = [0.5, 0.8, 1.0, 1.2, 1.4, 1.6];

fn main() {
    println!("| w | size | crossings | pieces (background, foreground) | truth pieces | Dice | iterations |");
    println!("|---|---|---|---|---|---|---|");
    for w in WEIGHTS {
        for size in [FAST_SIZE, FULL_SIZE] {
            let mut case = Figure::Fig2.cases(size).remove(0);
            case.params.length_weight = w;
            let outcome = figures::run(&case);
            let ph = &case.phantom;
            let truth = pixel_components(&ph.truth, ph.width, 2);
            println!(
                "| {w} | {size} | {} | {:?} | {truth:?} | {:.4} | {} |",
                outcome.topology.crossings,
                outcome.topology.components,
                outcome.dice,
                outcome.iterations
            );
        }
    }
}
