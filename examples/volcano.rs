//! User interaction on the DSC: Kass's volcano editing a finished segmentation.
//!
//! The paper's pipeline segments the Fig. 3 phantom. When it has converged,
//! the observer of [`Segmentation::run_until`] plays the user: it records the
//! result, switches the label flips off ([`Segmentation::params_mut`]; they
//! would relabel the dent's cells by their intensity) and erupts a volcano
//! placed 5 px outside the ring's outer edge ([`Segmentation::force_mut`]),
//! then lets the evolution converge again. The volcano (strength 4, radius
//! ρ = 8 px) repels the interface until its push, `4·exp(−r²/2ρ²)`, is
//! balanced by the region force and the rigidity: the ring's edge, 5 px from
//! the volcano before, ends about 10 px from it, a dent of about 5 px.
//! Elsewhere only noise-level jitter of the further relaxation (about 20
//! boundary pixels of 3400 object pixels at 128²).
//! Writes `out/volcano.png` (before | after).
//!
//! `cargo run --release --example volcano`

use dsc_seg::dim::D2;
use dsc_seg::io::Image2;
use dsc_seg::phantom::{self, Phantom2};
use dsc_seg::pipeline::save_overlay_png;
use dsc_seg::segment::models::Volcano;
use dsc_seg::segment::{
    Flow, ImageView, Models, SegmentError, SegmentParams, SegmentReport, Segmentation,
};
use nalgebra::Vector2;
use std::path::Path;

/// What the example produced (shared with the test in `tests/suite/forces.rs`).
pub struct Outcome {
    /// The phantom.
    pub phantom: Phantom2,
    /// The volcano's centre, in pixels.
    pub centre: (f64, f64),
    /// Labels when the pipeline first converged (before the eruption).
    pub before: Vec<u8>,
    /// Labels at the end.
    pub after: Vec<u8>,
    /// Iteration at which the volcano erupted.
    pub erupted_at: usize,
    /// The run's report.
    pub report: SegmentReport,
}

/// Runs the scenario on the `size`² Fig. 3 phantom; writes the "before" and
/// "after" overlays to `pictures`.
pub fn scenario(size: usize, pictures: Option<(&Path, &Path)>) -> Result<Outcome, SegmentError> {
    let phantom = phantom::shapes2d::fig3(size, 0.1, 11);
    let image = ImageView::new_2d(size, size, &phantom.image).expect("square image");
    let n = size as f64;
    // 5 px outside the ring's outer edge (ring centre (0.5, 0.4)·n, outer radius 0.28·n)
    let centre = (0.78 * n + 5.0, 0.40 * n);
    let volcano = Volcano::new(Vector2::new(centre.0, centre.1), 0.0, 8.0);
    let params = SegmentParams::new(2);
    let models = Models::paper(&params).with_force(volcano);
    let mut seg = Segmentation::<D2>::with_models(image, params, models)?;
    let background = Image2::from_raw(size, size, phantom.image.clone());
    let mut before = None;
    let mut erupted_at = 0;
    let report = seg.run_until(|s, rec| {
        if !s.converged() {
            return Flow::Continue;
        }
        if before.is_some() {
            return Flow::Stop;
        }
        // the user steps in
        before = Some(s.label_image());
        if let Some((path, _)) = pictures {
            save_overlay_png(s, &background, false, path).expect("picture written");
        }
        erupted_at = rec.iteration;
        s.params_mut().label_flips = false;
        s.force_mut::<Volcano<Vector2<f64>>>()
            .expect("the volcano is one of the models")
            .strength = 4.0;
        Flow::Continue
    });
    if let Some((_, path)) = pictures {
        save_overlay_png(&seg, &background, false, path).expect("picture written");
    }
    Ok(Outcome {
        before: before.unwrap_or_else(|| seg.label_image()),
        after: seg.label_image(),
        centre,
        erupted_at,
        report,
        phantom,
    })
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("out");
    std::fs::create_dir_all(&out)?;
    let (p0, p1) = (out.join("volcano_before.png"), out.join("volcano.png"));
    let o = scenario(128, Some((&p0, &p1)))?;
    let changed = o
        .before
        .iter()
        .zip(&o.after)
        .filter(|(a, b)| a != b)
        .count();
    println!(
        "volcano: erupted at iteration {}, stopped at {} ({:?}); {} pixels changed; -> {}, {}",
        o.erupted_at,
        o.report.iterations,
        o.report.stop_reason,
        changed,
        p0.display(),
        p1.display()
    );
    Ok(())
}
