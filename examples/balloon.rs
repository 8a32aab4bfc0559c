//! A balloon (pressure) force inflating a seed: Cohen's balloon on the DSC.
//!
//! A small seed disk in the trunk of the Fig. 3 phantom is phase 1. No region
//! force and no label flips: only
//!
//! - [`Balloon`]: pressure 1 along the outward normal of phase 1, faded to
//!   `1/(1 + P/k)` where the edge potential `P = |∇(G_σ ∗ I)|²` is large;
//! - [`EdgeAttraction`]: the snake's edge force `∇P`, which holds the balloon
//!   on the object's edge;
//! - [`Rigidity`]: the paper's bending term, keeping the front smooth.
//!
//! The seed inflates up the trunk, splits into the two branches of the ring,
//! whose fronts meet at the top and merge (a topology change the DSC handles
//! by itself), and stops at the edges. Writes `out/balloon.png`.
//!
//! `cargo run --release --example balloon`

use dsc_seg::dim::D2;
use dsc_seg::io::Image2;
use dsc_seg::phantom::{self, Phantom2};
use dsc_seg::pipeline::{mean_dice, save_overlay_png};
use dsc_seg::segment::models::{Balloon, EdgeAttraction, EdgeMap, Rigidity};
use dsc_seg::segment::{
    ImageView, Init, InitDisk, Models, SegmentError, SegmentParams, SegmentReport, Segmentation,
};
use std::path::Path;
use std::sync::Arc;

/// What the example produced (shared with the test in `tests/suite/forces.rs`).
pub struct Outcome {
    /// The phantom.
    pub phantom: Phantom2,
    /// Labels per pixel at the start (the seed) and at the end.
    pub initial: Vec<u8>,
    /// Final labels per pixel (0 background, 1 inflated).
    pub labels: Vec<u8>,
    /// The run's report.
    pub report: SegmentReport,
    /// Components of the inflated phase at the end.
    pub components: usize,
}

/// Runs the balloon on the `size`² Fig. 3 phantom; writes the overlay to `picture`.
pub fn scenario(size: usize, picture: Option<&Path>) -> Result<Outcome, SegmentError> {
    let phantom = phantom::shapes2d::fig3(size, 0.05, 3);
    let image = ImageView::new_2d(size, size, &phantom.image).expect("square image");
    let seed = phantom::shapes2d::fig3_seed(size);
    let mut params = SegmentParams::new(2);
    params.init = Init::Disks(vec![InitDisk {
        x: seed.x,
        y: seed.y,
        r: seed.r,
        phase: 1,
    }]);
    params.max_iterations = 400;
    // A balloon must bend into narrow branches: a stiffer curve (the default
    // β = 5, tuned against image noise) stops at the branch entrances.
    params.rigidity = 1.0;
    let edges = Arc::new(EdgeMap::new(&image, 1.5));
    let models = Models::empty()
        .with_force(Balloon::new(1, 1.0).with_edge_stop(edges.clone(), 0.05))
        .with_force(EdgeAttraction::new(edges, 1.0))
        .with_force(Rigidity::new(params.rigidity));
    let mut seg = Segmentation::<D2>::with_models(image, params, models)?;
    let initial = raw_labels(&seg);
    let report = seg.run(|_| {});
    if let Some(path) = picture {
        let img = Image2::from_raw(size, size, phantom.image.clone());
        save_overlay_png(&seg, &img, false, path).expect("picture written");
    }
    Ok(Outcome {
        initial,
        labels: raw_labels(&seg),
        components: seg.complex().components(1),
        report,
        phantom,
    })
}

/// Mesh labels per pixel (no reordering by mean: phase 1 is the balloon).
fn raw_labels(seg: &Segmentation<'_, D2>) -> Vec<u8> {
    let order = seg.phase_order();
    // label_image orders phases by mean; undo that so that 1 stays the balloon.
    let mut inverse = vec![0u8; order.len()];
    for (l, &rank) in order.iter().enumerate() {
        inverse[rank as usize] = l as u8;
    }
    seg.label_image()
        .into_iter()
        .map(|r| inverse[r as usize])
        .collect()
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("out");
    std::fs::create_dir_all(&out)?;
    let picture = out.join("balloon.png");
    let o = scenario(128, Some(&picture))?;
    let ph = &o.phantom;
    println!(
        "balloon: Dice {:.3} (seed {:.3}), {} iterations ({:?}), {} component(s) of the inflated phase -> {}",
        mean_dice(&o.labels, &ph.truth, 2),
        mean_dice(&o.initial, &ph.truth, 2),
        o.report.iterations,
        o.report.stop_reason,
        o.components,
        picture.display()
    );
    Ok(())
}
