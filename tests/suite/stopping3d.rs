//! The 3D stopping rule around flip rounds: a round that relabels only a few
//! noise-sized cells along settled interfaces does not buy a further energy
//! plateau, and one that comes on a plateau ends the run.

use crate::common::assert_valid;
use dsc_seg::dim::D3;
use dsc_seg::phantom::shapes3d;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{ImageView, SegmentParams, SegmentReport, Segmentation};

/// On the 32³ torus (σ 0.1) the energy is on a plateau when the flip round
/// of iteration 21 relabels a few dozen of about 10 000 cells: the default
/// ends the run there (then the fine finish), where counting the round's
/// energy as a new low ran ten iterations more for the same Dice.
#[test]
fn a_quiet_flip_round_on_a_plateau_ends_a_3d_run() {
    let ph = shapes3d::torus(32, 0.1, 1);
    let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
    let run = |params: SegmentParams| -> (SegmentReport, f64) {
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        let report = seg.run(|_| {});
        assert_valid(seg.complex());
        assert!(report.converged);
        (report, mean_dice(&seg.label_image(), &ph.truth, 2))
    };
    let quiet = SegmentParams::new_3d(2);
    let finish = quiet
        .sizing
        .finish
        .expect("two-phase 3D runs finish")
        .iterations;
    let mut counted = quiet.clone();
    counted.quiet_round_fraction = 0.0;
    let (counted, counted_dice) = run(counted);
    let (quiet, quiet_dice) = run(quiet);

    let round = quiet.history[20].clone();
    assert_eq!(round.iteration, 21);
    assert!(
        round.flips > 0 && (round.flips as f64) < 0.01 * round.cells as f64,
        "the round at 21 flipped {} of {} cells",
        round.flips,
        round.cells
    );
    assert_eq!(quiet.iterations, 21 + finish, "{:?}", quiet.history);
    assert!(
        counted.iterations >= quiet.iterations + 5,
        "{} iterations with the round counted, {} without",
        counted.iterations,
        quiet.iterations
    );
    assert!(
        quiet_dice > counted_dice - 0.002,
        "Dice {quiet_dice} ended at the quiet round, {counted_dice} counting it"
    );
}
