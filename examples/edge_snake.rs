//! The classical snake's edge force on the DSC (Kass et al.).
//!
//! The initial contour is the true outline of the benchmark two-phase
//! phantom grown by 3 pixels (as a user's rough outline, or a previous
//! frame's result, would be). No region force and no label flips: only
//!
//! - [`EdgeAttraction`]: `∇P / max|∇P|` with the edge potential
//!   `P = |∇(G_σ ∗ I)|²` of the image smoothed with σ = 1.5 px, which points
//!   towards the nearest large gradient within a capture range of about 2σ;
//! - [`Rigidity`]: the paper's bending term (eq. 2), the snake's internal force.
//!
//! Every interface moves onto the nearest edge: the disk, the annulus (both
//! its boundaries), the plate and its holes, the ellipse and the thin bar.
//! Writes `out/edge_snake.png`.
//!
//! `cargo run --release --example edge_snake`

use dsc_seg::dim::D2;
use dsc_seg::io::Image2;
use dsc_seg::phantom::{self, Phantom2};
use dsc_seg::pipeline::{mean_dice, save_overlay_png};
use dsc_seg::segment::models::{EdgeAttraction, EdgeMap, Rigidity};
use dsc_seg::segment::{
    ImageView, Init, Models, SegmentError, SegmentParams, SegmentReport, Segmentation,
};
use std::path::Path;
use std::sync::Arc;

/// What the example produced (shared with the test in `tests/suite/forces.rs`).
pub struct Outcome {
    /// The phantom.
    pub phantom: Phantom2,
    /// The initial labels (the truth grown by `grow` pixels).
    pub initial: Vec<u8>,
    /// Final labels per pixel (0 background, 1 foreground).
    pub labels: Vec<u8>,
    /// The run's report.
    pub report: SegmentReport,
}

/// Pixels within `r` of a foreground pixel of `labels` (`n × n`).
pub fn grow(labels: &[u8], n: usize, r: usize) -> Vec<u8> {
    let ri = r as i64;
    let mut out = vec![0u8; labels.len()];
    for y in 0..n as i64 {
        for x in 0..n as i64 {
            let hit = (-ri..=ri).any(|dy| {
                (-ri..=ri).any(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    dx * dx + dy * dy <= ri * ri
                        && u >= 0
                        && v >= 0
                        && u < n as i64
                        && v < n as i64
                        && labels[(v * n as i64 + u) as usize] == 1
                })
            });
            out[(y * n as i64 + x) as usize] = hit as u8;
        }
    }
    out
}

/// Runs the edge-attracted snake on the `size`² two-phase phantom; writes
/// the overlay to `picture`.
pub fn scenario(size: usize, picture: Option<&Path>) -> Result<Outcome, SegmentError> {
    let phantom = phantom::shapes2d::two_phase(size, 0.05, 5);
    let image = ImageView::new_2d(size, size, &phantom.image).expect("square image");
    let initial = grow(&phantom.truth, size, 3);
    let mut params = SegmentParams::new(2);
    params.init = Init::Labels {
        labels: initial.clone(),
    };
    params.max_iterations = 300;
    let edges = Arc::new(EdgeMap::new(&image, 1.5));
    let models = Models::empty()
        .with_force(EdgeAttraction::new(edges, 1.0))
        .with_force(Rigidity::new(params.rigidity));
    let mut seg = Segmentation::<D2>::with_models(image, params, models)?;
    let report = seg.run(|_| {});
    if let Some(path) = picture {
        let img = Image2::from_raw(size, size, phantom.image.clone());
        save_overlay_png(&seg, &img, false, path).expect("picture written");
    }
    Ok(Outcome {
        labels: seg.label_image(),
        initial,
        report,
        phantom,
    })
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("out");
    std::fs::create_dir_all(&out)?;
    let picture = out.join("edge_snake.png");
    let o = scenario(256, Some(&picture))?;
    let ph = &o.phantom;
    println!(
        "edge snake: Dice {:.3} (initial outline {:.3}), {} iterations ({:?}) -> {}",
        mean_dice(&o.labels, &ph.truth, 2),
        mean_dice(&o.initial, &ph.truth, 2),
        o.report.iterations,
        o.report.stop_reason,
        picture.display()
    );
    Ok(())
}
