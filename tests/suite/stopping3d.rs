//! The 3D stopping rule around flip rounds: a plateau reached before the
//! second flip round brings that round forward, a round that relabels only
//! a few noise-sized cells along settled interfaces does not buy a further
//! energy plateau, and one that comes on a plateau ends the run; with the
//! settle rate, an energy whose fall has slowed counts as the plateau.

use crate::common::assert_valid;
use dsc_seg::dim::D3;
use dsc_seg::phantom::shapes3d;
use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::{ImageView, SegmentParams, SegmentReport, Segmentation};

/// On the 32³ torus (σ 0.1) the energy reaches its plateau before
/// iteration 21, the second regular flip round: the settle round comes
/// right then and relabels a few dozen of about 10 000 cells, so the default
/// ends the run there (then the fine finish), where counting the round's
/// flips as a relabelling ran on for a further plateau at the same Dice.
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
    // The plateau's rule alone (without the settle rate's, tested below).
    let mut quiet = SegmentParams::new_3d(2);
    quiet.settle_rate = 0.0;
    let finish = quiet
        .sizing
        .finish
        .expect("two-phase 3D runs finish")
        .iterations;
    let mut counted = quiet.clone();
    counted.quiet_round_fraction = 0.0;
    let (counted, counted_dice) = run(counted);
    let (quiet, quiet_dice) = run(quiet);

    let settled = quiet.iterations - finish;
    let round = quiet.history[settled - 1].clone();
    assert!(
        round.iteration < 21,
        "the run settled at {}, the round was not brought forward",
        round.iteration
    );
    assert!(
        round.flips > 0 && (round.flips as f64) < 0.01 * round.cells as f64,
        "the round at {} flipped {} of {} cells",
        round.iteration,
        round.flips,
        round.cells
    );
    assert!(
        quiet.history[1..settled - 1].iter().all(|r| r.flips == 0),
        "a round between the first and the settle round: {:?}",
        quiet.history
    );
    assert!(
        counted.iterations >= quiet.iterations + 3,
        "{} iterations with the round counted, {} without",
        counted.iterations,
        quiet.iterations
    );
    assert!(
        quiet_dice > counted_dice - 0.002,
        "Dice {quiet_dice} ended at the quiet round, {counted_dice} counting it"
    );
}

/// With `quiet_round_plateau` 0 (the coarse pass's) the first quiet flip
/// round ends the run whatever the energy did before it: on the 32³ torus
/// the round at 21, with a plateau too long to end the run sooner; with the
/// default (half the plateau) the run goes on past it.
#[test]
fn a_quiet_round_ends_the_run_at_once_with_quiet_round_plateau_0() {
    let ph = shapes3d::torus(32, 0.1, 1);
    let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
    let run = |quiet_round_plateau: Option<usize>| -> SegmentReport {
        let mut params = SegmentParams::new_3d(2);
        params.converge_plateau = Some(50);
        params.sizing.finish = None;
        params.quiet_round_plateau = quiet_round_plateau;
        params.settle_rate = 0.0;
        params.max_iterations = 30;
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        let report = seg.run(|_| {});
        assert_valid(seg.complex());
        report
    };
    let at_once = run(Some(0));
    assert!(at_once.converged);
    assert_eq!(at_once.iterations, 21, "{:?}", at_once.history);
    let round = &at_once.history[20];
    assert!(
        round.flips > 0 && (round.flips as f64) < 0.01 * round.cells as f64,
        "the round at 21 flipped {} of {} cells",
        round.flips,
        round.cells
    );
    let default = run(None);
    assert!(
        default.iterations > 21,
        "the default stopped at {}",
        default.iterations
    );
}

/// With the settle rate (the 3D default) the settle round comes once the
/// energy's fall has slowed, before its plateau: on the 48³ torus (σ 0.1)
/// the round is quiet and ends the run (then the fine finish) in under half
/// the iterations of the plateau's rule alone, at about the same Dice.
#[test]
fn a_slowed_energy_fall_brings_the_settle_round_forward() {
    let ph = shapes3d::torus(48, 0.1, 1);
    let view = ImageView::new_3d([ph.nx, ph.ny, ph.nz], &ph.image).unwrap();
    let run = |settle_rate: f64| -> (SegmentReport, f64) {
        let mut params = SegmentParams::new_3d(2);
        params.settle_rate = settle_rate;
        let mut seg = Segmentation::<D3>::new(view, params).unwrap();
        let report = seg.run(|_| {});
        assert_valid(seg.complex());
        assert!(report.converged);
        (report, mean_dice(&seg.label_image(), &ph.truth, 2))
    };
    let (slowed, slowed_dice) = run(SegmentParams::new_3d(2).settle_rate);
    let (plateau, plateau_dice) = run(0.0);
    assert!(
        2 * slowed.iterations <= plateau.iterations,
        "{} iterations with the settle rate, {} without",
        slowed.iterations,
        plateau.iterations
    );
    let rounds = slowed.history[1..].iter().filter(|r| r.flips > 0).count();
    assert_eq!(rounds, 1, "one settle round: {:?}", slowed.history);
    assert!(
        slowed_dice > plateau_dice - 0.002,
        "Dice {slowed_dice} with the settle rate, {plateau_dice} without"
    );
}
