//! Paper-style panels of an [`Outcome`]: PNGs (and a GIF) in a directory,
//! plus a one-line summary for the results table.

use super::encode::{save_delta_gif, save_palette_png};
use super::{Case, Mesh, Outcome, Snapshot};
use crate::io::{Image2, IoError, Overlay};
use image::RgbaImage;
use std::path::Path;

/// Output pixels per image pixel of the panels (a 256 px image gives 512 px panels).
pub const PANEL_SCALE: f32 = 2.0;
/// Interface line width in output pixels.
pub const LINE_WIDTH: f32 = 3.0;
/// Mesh line width in output pixels.
pub const MESH_WIDTH: f32 = 1.0;
/// Opacity of the white mesh lines.
pub const MESH_ALPHA: f32 = 0.55;
/// Colours of a panel PNG's palette.
pub const PNG_COLORS: usize = 48;
/// Most frames of a GIF (iterations are subsampled evenly beyond this).
pub const MAX_GIF_FRAMES: usize = 40;
/// Output pixels per image pixel of the GIF frames.
pub const GIF_SCALE: f32 = 1.5;

/// One written panel.
#[derive(Clone, Debug)]
pub struct Panel {
    /// File name inside the output directory.
    pub file: String,
    /// What it shows, e.g. "iteration 28" or "paper's 82 → our final (61)".
    pub caption: String,
}

fn render(image: &Image2, mesh: &Mesh, scale: f32) -> RgbaImage {
    let mut ov = Overlay::new(image, &mesh.points, &mesh.triangles, &mesh.labels).with_scale(scale);
    ov.line_width = LINE_WIDTH * scale / PANEL_SCALE;
    ov.mesh_width = Some(MESH_WIDTH * scale / PANEL_SCALE);
    ov.mesh_alpha = MESH_ALPHA;
    ov.to_rgba_image()
}

/// Writes the panels of `case`/`outcome` into `dir` and returns them in
/// paper order: original and initial labelling (where the paper shows
/// them), the paper's iterations (those
/// after our convergence replaced by our final state, once), final; plus
/// `NAME.gif` for animated cases.
pub fn write(case: &Case, outcome: &Outcome, dir: &Path) -> Result<Vec<Panel>, IoError> {
    std::fs::create_dir_all(dir).map_err(|e| IoError::write(dir, e))?;
    let ph = &case.phantom;
    let image = Image2::from_raw(ph.width, ph.height, ph.image.clone());
    let mut panels = Vec::new();
    let mut save = |file: String, caption: String, rgba: &RgbaImage| -> Result<(), IoError> {
        save_palette_png(dir.join(&file), rgba, PNG_COLORS)?;
        panels.push(Panel { file, caption });
        Ok(())
    };
    let n = &case.name;
    let empty = Mesh::default();
    if case.original {
        save(
            format!("fig{}_original.png", case.figure.number()),
            "original".into(),
            &render(&image, &empty, PANEL_SCALE),
        )?;
    }
    if case.initial {
        save(
            format!("{n}_init.png"),
            "initial labelling".into(),
            &render(&image, &outcome.initial.mesh, PANEL_SCALE),
        )?;
    }
    // The paper's iterations: ours where the run got that far; otherwise
    // the iteration at the same fraction of our run (if recorded), else the
    // final state.
    let find = |k: usize| {
        outcome
            .snapshots
            .iter()
            .chain(&outcome.frames)
            .find(|s| s.iteration == k && k < outcome.iterations)
    };
    let mut late = Vec::new();
    for &k in &case.snapshots {
        if let Some(s) = find(k) {
            save(
                format!("{n}_it{k:03}.png"),
                format!("iteration {k}"),
                &render(&image, &s.mesh, PANEL_SCALE),
            )?;
            continue;
        }
        let paper = case.figure.paper_iterations().unwrap_or(k).max(1);
        let ours = (k * outcome.converged_at + paper / 2) / paper;
        match find(ours) {
            Some(s) if ours < outcome.converged_at => save(
                format!("{n}_it{ours:03}.png"),
                format!("iteration {ours} (stands for the paper's {k}: same fraction of the run)"),
                &render(&image, &s.mesh, PANEL_SCALE),
            )?,
            _ => late.push(k),
        }
    }
    let fin = outcome.iterations;
    let caption = if late.is_empty() {
        format!("final, iteration {fin}")
    } else {
        let ks: Vec<String> = late.iter().map(|k| k.to_string()).collect();
        format!(
            "final, iteration {fin} (stands for the paper's {})",
            ks.join(", ")
        )
    };
    save(
        format!("{n}_final.png"),
        caption,
        &render(&image, &outcome.last.mesh, PANEL_SCALE),
    )?;
    if case.animate && !outcome.frames.is_empty() {
        write_gif(&image, outcome, &dir.join(format!("{n}.gif")))?;
        panels.push(Panel {
            file: format!("{n}.gif"),
            caption: "evolution (animated)".into(),
        });
    }
    Ok(panels)
}

/// Writes the evolution as a GIF: initial labelling, up to
/// [`MAX_GIF_FRAMES`] evenly spaced iterations, and a held final frame.
fn write_gif(image: &Image2, outcome: &Outcome, path: &Path) -> Result<(), IoError> {
    let all: Vec<&Snapshot> = std::iter::once(&outcome.initial)
        .chain(&outcome.frames)
        .collect();
    let stride = all.len().div_ceil(MAX_GIF_FRAMES).max(1);
    let mut picked: Vec<&Snapshot> = all.iter().step_by(stride).copied().collect();
    if picked.last().map(|s| s.iteration) != Some(outcome.last.iteration) {
        picked.push(&outcome.last);
    }
    let frames: Vec<RgbaImage> = picked
        .iter()
        .map(|s| render(image, &s.mesh, GIF_SCALE))
        .collect();
    let mut delays = vec![12u16; frames.len()];
    delays[0] = 80;
    if let Some(d) = delays.last_mut() {
        *d = 250;
    }
    save_delta_gif(path, &frames, &delays)
}

/// One row of the results table (Markdown).
pub fn summary_row(case: &Case, outcome: &Outcome) -> String {
    let figure = case.figure;
    let paper = figure
        .paper_iterations()
        .map_or("–".to_string(), |k| k.to_string());
    let stop = if outcome.driver_converged {
        "driver's rule"
    } else if outcome.converged {
        "labelling settled"
    } else {
        "iteration cap"
    };
    let per: Vec<String> = outcome
        .dice_per_phase
        .iter()
        .map(|d| format!("{d:.3}"))
        .collect();
    format!(
        "| {} | {} | {} | {} ({stop}, {} run) | {:.4} ({}) | {:.2} s | L = {:.1}, {} triangles |",
        figure.number(),
        case.name,
        paper,
        outcome.converged_at,
        outcome.iterations,
        outcome.dice,
        per.join(" / "),
        outcome.seconds,
        outcome.edge_length,
        outcome.triangles,
    )
}
