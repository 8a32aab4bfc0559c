//! Prints, per iteration of a default 3D run on a volume with ground truth,
//! the energy, the flips, the largest move, the step, the cells, the mean
//! Dice of the labels at that point against the truth and against the
//! previous iteration's labels, and the seconds the iteration took (wall
//! clock, without the scoring): what the stopping rule sees against what it
//! is meant to judge, from one run instead of one run per
//! `--max-iterations N`, and whether the labels still move when it stops.
//!
//! `cargo run --release --example dice_trajectory -- VOLUME TRUTH PHASES [EVERY] [AFTER] [--no-coarse-pass] [--dump DIR]`
//!
//! `TRUTH` is a label volume of the same size (any distinct values, one per
//! phase; phases are matched to labels by the best of all pairings). The Dice
//! against the truth is scored every `EVERY` iterations (default 1) and at
//! every flip round; with `AFTER` the run goes on that many iterations past
//! convergence (the stopping rule and the fine finish, if any). The
//! iterations listed are those at full resolution, after the coarse pass
//! where the default runs one (`SegmentParams::coarse_pass`);
//! `--no-coarse-pass` runs without it. `--dump DIR` writes each iteration's
//! labels to `DIR/labels_NNN.u8` (one byte per voxel, x fastest), to
//! compare two runs iteration by iteration.

use dsc_seg::dim::D3;
use dsc_seg::io::volume::Volume;
use dsc_seg::segment::{Flow, ImageView, SegmentParams, Segmentation};

/// Mean Dice over the truth's phases of the best one-to-one pairing of
/// truth phases with labels (both `0..phases`).
fn matched_mean_dice(labels: &[u8], truth: &[u8], phases: usize) -> f64 {
    let mut counts = vec![0u64; phases * phases];
    let (mut truth_sizes, mut label_sizes) = (vec![0u64; phases], vec![0u64; phases]);
    for (&l, &t) in labels.iter().zip(truth) {
        let (l, t) = (l as usize, t as usize);
        counts[t * phases + l] += 1;
        truth_sizes[t] += 1;
        label_sizes[l] += 1;
    }
    let mut best = 0.0f64;
    for_each_permutation(phases, &mut |perm| {
        let total: f64 = (0..phases)
            .map(|t| {
                let l = perm[t];
                let sizes = truth_sizes[t] + label_sizes[l];
                if sizes == 0 {
                    1.0
                } else {
                    2.0 * counts[t * phases + l] as f64 / sizes as f64
                }
            })
            .sum();
        best = best.max(total / phases as f64);
    });
    best
}

/// Calls `visit` with every permutation of `0..n` (Heap's algorithm).
fn for_each_permutation(n: usize, visit: &mut impl FnMut(&[usize])) {
    fn heap(k: usize, perm: &mut Vec<usize>, visit: &mut impl FnMut(&[usize])) {
        if k <= 1 {
            visit(perm);
            return;
        }
        for i in 0..k {
            heap(k - 1, perm, visit);
            let j = if k % 2 == 0 { i } else { 0 };
            perm.swap(j, k - 1);
        }
    }
    let mut perm: Vec<usize> = (0..n).collect();
    heap(n, &mut perm, visit);
}

/// The truth volume's values as dense labels `0..K` by increasing value.
fn dense_truth(truth: &Volume) -> Vec<u8> {
    let mut values: Vec<f32> = truth.data().to_vec();
    values.sort_by(f32::total_cmp);
    values.dedup();
    truth
        .data()
        .iter()
        .map(|v| values.partition_point(|x| x < v) as u8)
        .collect()
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let no_coarse_pass = args.iter().any(|a| a == "--no-coarse-pass");
    args.retain(|a| a != "--no-coarse-pass");
    let dump = args.iter().position(|a| a == "--dump").map(|i| {
        let dir = args.remove(i + 1);
        args.remove(i);
        dir
    });
    if args.len() < 3 {
        eprintln!("usage: dice_trajectory VOLUME TRUTH PHASES [EVERY] [AFTER] [--no-coarse-pass] [--dump DIR]");
        std::process::exit(2);
    }
    let volume = Volume::load(&args[0]).expect("volume");
    let truth = dense_truth(&Volume::load(&args[1]).expect("truth"));
    let phases: usize = args[2].parse().expect("PHASES");
    let every: usize = args.get(3).map_or(1, |s| s.parse().expect("EVERY"));
    let after: usize = args.get(4).map_or(0, |s| s.parse().expect("AFTER"));
    let mut params = SegmentParams::new_3d(phases);
    params.coarse_pass = !no_coarse_pass;
    let flip_interval = params.flip_interval;
    let view = ImageView::new_3d(volume.dims(), volume.data())
        .and_then(|v| v.with_spacing(volume.frame().domain_scale))
        .expect("volume view");
    let mut seg = Segmentation::<D3>::new(view, params).expect("segmentation");
    let mut converged_at = None;
    let mut previous: Option<Vec<u8>> = None;
    println!("iteration energy flips max_move step cells dice dice_previous seconds");
    let mut clock = std::time::Instant::now();
    seg.run_until(|s, r| {
        let seconds = clock.elapsed().as_secs_f64();
        let flip_round = (r.iteration - 1) % flip_interval == 0;
        let labels = s.label_image();
        let dice = if r.iteration % every == 0 || flip_round || s.converged() {
            format!("{:.4}", matched_mean_dice(&labels, &truth, phases))
        } else {
            "-".into()
        };
        let dice_previous = previous.as_ref().map_or("-".into(), |p| {
            format!("{:.4}", matched_mean_dice(&labels, p, phases))
        });
        if let Some(dir) = &dump {
            std::fs::write(format!("{dir}/labels_{:03}.u8", r.iteration), &labels).expect("dump");
        }
        println!(
            "{} {:.3} {} {:.4} {:.4} {} {} {} {:.3}{}",
            r.iteration,
            r.energy,
            r.flips,
            r.max_displacement_across,
            s.step_fraction(),
            r.cells,
            dice,
            dice_previous,
            seconds,
            if s.converged() { " converged" } else { "" }
        );
        previous = Some(labels);
        clock = std::time::Instant::now();
        if s.converged() && converged_at.is_none() {
            converged_at = Some(r.iteration);
        }
        match converged_at {
            Some(at) if r.iteration >= at + after => Flow::Stop,
            _ => Flow::Continue,
        }
    });
}
