//! A fixed workload for instruction counts of the cell statistics (the
//! rasteriser and the sums), one thread: every cell of the 512² two-phase
//! box mesh and of the same mesh after 20 iterations, integrated `ROUNDS`
//! times (5, or the first argument). Prints a checksum of the statistics'
//! bits, so a change that is meant to keep them can be checked in the same
//! run, and the wall-clock time per round:
//!
//! `valgrind --tool=callgrind --toggle-collect=*measured_rounds* target/release/examples/statistics_workload`
use dsc_seg::complex::Complex;
use dsc_seg::dim::D2;
use dsc_seg::phantom::shapes2d;
use dsc_seg::segment::integrate::cell_stats;
use dsc_seg::segment::{ImageView, SegmentParams, Segmentation};

/// The measured part: returns a checksum of every statistic's bits.
#[inline(never)]
fn measured_rounds(rounds: usize, meshes: &[&Complex<D2>], image: &ImageView<'_>) -> u64 {
    let mut h = 0u64;
    for _ in 0..rounds {
        for mesh in meshes {
            for c in mesh.cell_ids() {
                let s = cell_stats::<D2>(image, &mesh.cell_points(c)[..3]);
                for x in [s.sum.to_bits(), s.sum_sq.to_bits(), s.count as u64] {
                    h = (h ^ x).wrapping_mul(0x100000001b3);
                }
            }
        }
    }
    h
}

fn main() {
    let p = shapes2d::two_phase(512, 0.2, 1);
    let image = ImageView::new_2d(p.width, p.height, &p.image).unwrap();
    let mut seg = Segmentation::<D2>::new(image, SegmentParams::new(2)).unwrap();
    let start = seg.complex().clone();
    for _ in 0..20 {
        seg.step();
    }
    let rounds = std::env::args()
        .nth(1)
        .map_or(5, |a| a.parse().expect("ROUNDS"));
    let t = std::time::Instant::now();
    let sum = measured_rounds(rounds, &[&start, seg.complex()], &image);
    let per_round = t.elapsed().as_secs_f64() / rounds as f64;
    println!("checksum {sum:016x}, {:.1} µs per round", per_round * 1e6);
}
