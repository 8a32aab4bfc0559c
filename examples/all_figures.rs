//! Regenerates every figure of `paper/` (Figs. 2–6) and the results table
//! `paper/figures/results.md`.
//!
//! ```sh
//! cargo run --release --example all_figures
//! ```

mod common;

use dsc_seg::figures::Figure;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let t = std::time::Instant::now();
    let mut table = String::from(
        "| Fig. | run | paper's iterations | our iterations at convergence | Dice (per phase) | time | mesh |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for figure in Figure::ALL {
        for row in common::reproduce(figure)? {
            table.push_str(&row);
            table.push('\n');
        }
    }
    let path = common::out_dir().join("results.md");
    std::fs::write(&path, table)?;
    println!(
        "wrote {} in {:.1} s",
        path.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}
