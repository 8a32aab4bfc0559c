//! Shared driver of the figure examples: run a figure at full size, write
//! its panels into `paper/figures/` and print its row of the results table.

use dsc_seg::figures::{self, panels, Figure, FULL_SIZE};
use std::path::{Path, PathBuf};

/// Where the panels go: `paper/figures/` of the crate (or `$DSC_FIGURES_OUT`).
pub fn out_dir() -> PathBuf {
    std::env::var_os("DSC_FIGURES_OUT").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("paper/figures"),
        PathBuf::from,
    )
}

/// Runs every case of `figure`, writes its panels and returns the table rows.
pub fn reproduce(figure: Figure) -> Result<Vec<String>, Box<dyn std::error::Error>> {
    let dir = out_dir();
    let mut rows = Vec::new();
    for case in figure.cases(FULL_SIZE) {
        let outcome = figures::run(&case);
        let written = panels::write(&case, &outcome, &dir)?;
        let row = panels::summary_row(&case, &outcome);
        println!("{row}");
        for p in &written {
            println!("    {}: {}", p.file, p.caption);
        }
        println!(
            "    components {:?} -> {:?}, triple junctions {} {:?}, crossings {}, interface {:.0} px",
            outcome.initial_topology.components,
            outcome.topology.components,
            outcome.topology.triple_junctions,
            outcome.topology.junction_phases,
            outcome.topology.crossings,
            outcome.topology.interface_length
        );
        rows.push(row);
    }
    Ok(rows)
}
