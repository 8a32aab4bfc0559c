//! Reproduction of the paper's Figures 2–6 (ICPR 2014, section IV).
//!
//! Each figure is a [`Case`]: a phantom from [`crate::phantom::shapes2d`] with
//! a fixed seed, the paper's settings (initialisation, label flips on or
//! off, edge length) and the iterations the paper shows. [`run`] evolves it
//! and returns an [`Outcome`] with mesh snapshots, Dice against the ground
//! truth and topological measurements; [`panels`] writes the paper-style
//! PNG panels (and GIF) of an outcome. The examples `fig2_two_phase` …
//! `fig6_three_phase_user_init` and `all_figures` are thin wrappers, and the
//! test suite runs the same cases at [`FAST_SIZE`].
//!
//! Sizes scale with the image: every length below is given for a
//! [`FULL_SIZE`] image and multiplied by `size / FULL_SIZE`.

pub mod encode;
pub mod panels;

use crate::complex::Complex;
use crate::dim::D2;
use crate::phantom::{self, shapes2d, Phantom2};
use crate::segment::{ImageView, Init, InitDisk, Raster, SegmentParams, Segmentation};
use std::time::Instant;

/// Image size of the published panels.
pub const FULL_SIZE: usize = 256;
/// Image size of the fast variants run by the test suite.
pub const FAST_SIZE: usize = 128;
/// Seed of the phantom noise (fixed so that every run draws the same image).
pub const SEED: u64 = 2014;
/// Standard deviation of the additive Gaussian noise (intensities in `[0, 1]`).
pub const NOISE_SIGMA: f64 = 0.1;
/// Edge length L of Figs. 2, 3, 4 and 6 at [`FULL_SIZE`] (the paper does not give it).
pub const EDGE_LENGTH: f64 = 6.0;
/// The two edge lengths of Fig. 5 at [`FULL_SIZE`], as in the paper.
pub const FIG5_EDGE_LENGTHS: [f64; 2] = [10.0, 15.0];
/// Iteration cap of every run.
pub const MAX_ITERATIONS: usize = 400;
/// Convergence window: the run has converged at iteration `k` when the pixel
/// labelling of iteration `k + SETTLE_WINDOW` differs from that of `k` in at
/// most [`SETTLE_FRACTION`] of the pixels and no label flipped in between.
pub const SETTLE_WINDOW: usize = 10;
/// See [`SETTLE_WINDOW`].
pub const SETTLE_FRACTION: f64 = 0.001;

/// The figures of the paper.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Figure {
    /// Two phases, range initialisation, label flips (paper: 25 iterations).
    Fig2,
    /// One region grown from a disk, no flips (paper: 82 iterations).
    Fig3,
    /// Four phases, interval initialisation, label flips (paper: 30 iterations).
    Fig4,
    /// Three phases at L = 10 and L = 15.
    Fig5,
    /// Three phases from user regions, no flips (paper: 170 iterations).
    Fig6,
}

impl Figure {
    /// All figures in order.
    pub const ALL: [Figure; 5] = [
        Figure::Fig2,
        Figure::Fig3,
        Figure::Fig4,
        Figure::Fig5,
        Figure::Fig6,
    ];

    /// The paper's number of the figure.
    pub fn number(self) -> u32 {
        match self {
            Figure::Fig2 => 2,
            Figure::Fig3 => 3,
            Figure::Fig4 => 4,
            Figure::Fig5 => 5,
            Figure::Fig6 => 6,
        }
    }

    /// The iteration count of the paper's last panel, if it gives one.
    pub fn paper_iterations(self) -> Option<usize> {
        match self {
            Figure::Fig2 => Some(25),
            Figure::Fig3 => Some(82),
            Figure::Fig4 => Some(30),
            Figure::Fig5 => None,
            Figure::Fig6 => Some(170),
        }
    }

    /// The figure's runs at image size `size` (two for Fig. 5, one otherwise).
    pub fn cases(self, size: usize) -> Vec<Case> {
        match self {
            Figure::Fig2 => vec![fig2(size)],
            Figure::Fig3 => vec![fig3(size)],
            Figure::Fig4 => vec![fig4(size)],
            Figure::Fig5 => FIG5_EDGE_LENGTHS.iter().map(|&l| fig5(size, l)).collect(),
            Figure::Fig6 => vec![fig6(size)],
        }
    }
}

/// One segmentation run of a figure.
#[derive(Clone, Debug)]
pub struct Case {
    /// The figure it belongs to.
    pub figure: Figure,
    /// File stem of its outputs (`fig3`, `fig5_L10`, …).
    pub name: String,
    /// Whether the paper shows the original image (written once per figure).
    pub original: bool,
    /// Whether the paper shows the initial labelling.
    pub initial: bool,
    /// Input image and ground truth.
    pub phantom: Phantom2,
    /// Segmentation parameters.
    pub params: SegmentParams,
    /// Iterations the paper shows as panels (captured when reached).
    pub snapshots: Vec<usize>,
    /// Whether to keep every iteration for an animated GIF.
    pub animate: bool,
}

fn scaled(size: usize, length: f64) -> f64 {
    length * size as f64 / FULL_SIZE as f64
}

fn base_params(phases: usize, size: usize, edge_length: f64) -> SegmentParams {
    let mut p = SegmentParams::new(phases);
    p.edge_length = Some(scaled(size, edge_length));
    p.max_iterations = MAX_ITERATIONS;
    p
}

/// Fig. 2: two phases with crossings (checkerboard) and holes; the dynamic
/// range is bisected and label flips are on.
pub fn fig2(size: usize) -> Case {
    Case {
        figure: Figure::Fig2,
        name: "fig2".into(),
        original: true,
        initial: true,
        phantom: shapes2d::fig2(size, NOISE_SIGMA, SEED),
        params: base_params(2, size, EDGE_LENGTH),
        snapshots: vec![25],
        animate: false,
    }
}

/// Step of the region-growing figures (3 and 6), as a fraction of L per
/// iteration: the paper grows a whole object within 82–170 iterations, which
/// the default step (0.1 L) cannot do.
pub const GROWTH_STEP_FRACTION: f64 = 0.4;
/// Rigidity β of the region-growing figures (3 and 6): the default (5, tuned
/// for runs with label flips) stalls a front advancing along a narrow branch,
/// so Fig. 3 never merges within the iteration cap.
pub const GROWTH_RIGIDITY: f64 = 1.0;

/// The region-growing figures' parameters: flips off, the step and
/// rigidity above, and one step for every vertex (`step_gain` 1, the
/// paper's rule): with the 2D default gains Fig. 6's fronts met elsewhere
/// and swallowed the enclosed disk, which the paper shows as a hole.
fn growth_params(phases: usize, size: usize, init: Vec<InitDisk>) -> SegmentParams {
    let mut p = base_params(phases, size, EDGE_LENGTH);
    p.label_flips = false;
    p.step_fraction = GROWTH_STEP_FRACTION;
    p.step_gain = 1.0;
    p.rigidity = GROWTH_RIGIDITY;
    p.init = Init::Disks(init);
    p
}

/// Fig. 3: one region grown from a disk in the trunk of a branched object,
/// label flips off.
pub fn fig3(size: usize) -> Case {
    let seed = phantom::fig3_seed(size);
    let params = growth_params(
        2,
        size,
        vec![InitDisk {
            x: seed.x,
            y: seed.y,
            r: seed.r,
            phase: 1,
        }],
    );
    Case {
        figure: Figure::Fig3,
        name: "fig3".into(),
        original: false,
        initial: true,
        phantom: shapes2d::fig3(size, NOISE_SIGMA, SEED),
        params,
        snapshots: vec![3, 9, 28, 43, 45, 47, 82],
        animate: true,
    }
}

/// Fig. 4: four phases; the range is split into four intervals, flips on.
pub fn fig4(size: usize) -> Case {
    Case {
        figure: Figure::Fig4,
        name: "fig4".into(),
        original: true,
        initial: true,
        phantom: shapes2d::fig4(size, NOISE_SIGMA, SEED),
        params: base_params(4, size, EDGE_LENGTH),
        snapshots: vec![30],
        animate: false,
    }
}

/// Fig. 5: a dark/light blend with small details, three phases, flips on,
/// edge length `edge_length` (at [`FULL_SIZE`]; 10 or 15 in the paper).
pub fn fig5(size: usize, edge_length: f64) -> Case {
    Case {
        figure: Figure::Fig5,
        name: format!("fig5_L{edge_length}"),
        original: edge_length == FIG5_EDGE_LENGTHS[0],
        initial: false,
        phantom: shapes2d::fig5(size, NOISE_SIGMA, SEED),
        params: base_params(3, size, edge_length),
        snapshots: vec![],
        animate: false,
    }
}

/// Radius of the phase-2 seed of Fig. 6 at [`FULL_SIZE`].
const FIG6_PHASE2_SEED_RADIUS: f64 = 8.0;

/// The user initialisation of Fig. 6: the phantom's two phase-1 regions
/// ([`phantom::fig6_initial_regions`]) and a phase-2 seed in the separate
/// phase-2 disk (without flips a phase that starts with no cells never
/// appears). A phase-2 seed in the *enclosed* disk instead leaves thin
/// phase-2 slivers pinned between the two phase-1 fronts (a two-phase
/// crossing gets no force), so the regions never merge.
pub fn fig6_init(size: usize) -> Vec<InitDisk> {
    let s = size as f64;
    let mut disks: Vec<InitDisk> = phantom::fig6_initial_regions(size)
        .iter()
        .map(|r| InitDisk {
            x: r.disk.x,
            y: r.disk.y,
            r: r.disk.r,
            phase: u32::from(r.phase),
        })
        .collect();
    disks.push(InitDisk {
        x: 0.80 * s,
        y: 0.16 * s,
        r: scaled(size, FIG6_PHASE2_SEED_RADIUS),
        phase: 2,
    });
    disks
}

/// Fig. 6: three phases from user regions, flips off.
pub fn fig6(size: usize) -> Case {
    let params = growth_params(3, size, fig6_init(size));
    Case {
        figure: Figure::Fig6,
        name: "fig6".into(),
        original: false,
        initial: true,
        phantom: shapes2d::fig6(size, NOISE_SIGMA, SEED),
        params,
        snapshots: vec![110, 170],
        animate: true,
    }
}

/// A copy of the mesh in plain arrays (the input of [`crate::io::Overlay`]).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions in pixels.
    pub points: Vec<[f64; 2]>,
    /// Triangles as indices into `points`.
    pub triangles: Vec<[u32; 3]>,
    /// Mesh label per triangle (the phase it starts as).
    pub labels: Vec<u32>,
}

impl Mesh {
    fn of(complex: &Complex<D2>) -> Self {
        let a = complex.to_arrays();
        Mesh {
            points: a.points_2d(),
            triangles: a.triangles(),
            labels: a.labels.clone(),
        }
    }
}

/// The mesh after a given iteration (0: the initial labelling).
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Iterations done.
    pub iteration: usize,
    /// The mesh then.
    pub mesh: Mesh,
}

/// Topological measurements of a labelled mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Connected components (through shared edges) per mesh label.
    pub components: Vec<usize>,
    /// Vertices whose triangles carry three or more distinct labels.
    pub triple_junctions: usize,
    /// The distinct label sets (sorted) seen at those vertices.
    pub junction_phases: Vec<Vec<u8>>,
    /// Crossings: vertices where one label occurs in two separate pieces of
    /// the star but only two labels meet (a checkerboard corner).
    pub crossings: usize,
    /// Total interface length in pixels.
    pub interface_length: f64,
}

impl Topology {
    fn of(s: &Segmentation<'_, D2>, phases: usize) -> Self {
        let c = s.complex();
        let mut around = Vec::new();
        let (mut triple, mut crossings, mut sets) = (0, 0, Vec::new());
        for v in c.vertex_ids() {
            if !c.class(v).on_interface() {
                continue;
            }
            c.labels_around(v, &mut around);
            if around.len() >= 3 {
                triple += 1;
                let set: Vec<u8> = around.iter().map(|&l| l as u8).collect();
                if !sets.contains(&set) {
                    sets.push(set);
                }
            } else if c.count_phase_pieces(v) > 2 {
                crossings += 1;
            }
        }
        sets.sort();
        Topology {
            components: (0..phases).map(|l| c.components(l as _)).collect(),
            triple_junctions: triple,
            junction_phases: sets,
            crossings,
            interface_length: s.interface_measure(),
        }
    }
}

/// The result of [`run`].
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The initial labelling (iteration 0).
    pub initial: Snapshot,
    /// The meshes at the case's requested iterations that the run reached.
    pub snapshots: Vec<Snapshot>,
    /// Every iteration (only for animated cases), for the GIF.
    pub frames: Vec<Snapshot>,
    /// The final mesh.
    pub last: Snapshot,
    /// Iteration at which the labelling settled (see [`SETTLE_WINDOW`]);
    /// equal to `iterations` if it never did.
    pub converged_at: usize,
    /// Iterations run.
    pub iterations: usize,
    /// Whether the run stopped because it settled or the driver's own
    /// stopping rule held (rather than at [`MAX_ITERATIONS`]).
    pub converged: bool,
    /// Whether the driver's own stopping rule held.
    pub driver_converged: bool,
    /// Mean Dice over the ground-truth phases (labels matched by index).
    pub dice: f64,
    /// Dice per ground-truth phase.
    pub dice_per_phase: Vec<f64>,
    /// Wall time of the segmentation (setup and iterations, no file output), seconds.
    pub seconds: f64,
    /// Topology of the initial labelling.
    pub initial_topology: Topology,
    /// Topology of the final labelling.
    pub topology: Topology,
    /// Final edge length in pixels.
    pub edge_length: f64,
    /// Number of triangles at the end.
    pub triangles: usize,
}

/// The labelling per pixel by *mesh* label (pixel-centre rule).
fn mesh_label_image(s: &Segmentation<'_, D2>, image: &ImageView<'_>) -> Vec<u8> {
    let c = s.complex();
    let mut out = vec![0u8; image.len()];
    for t in c.cell_ids() {
        let l = c.label(t) as u8;
        let pts = c.cell_points(t);
        <D2 as Raster>::cell_pixels(image, &pts[..3], &mut |p| out[p] = l);
    }
    out
}

/// Dice per phase of `labels` against `truth` (phases `0..phases`).
pub fn dice(labels: &[u8], truth: &[u8], phases: usize) -> Vec<f64> {
    (0..phases as u8)
        .map(|k| {
            let tp = labels
                .iter()
                .zip(truth)
                .filter(|(a, b)| **a == k && **b == k)
                .count();
            let n = labels.iter().filter(|&&a| a == k).count()
                + truth.iter().filter(|&&b| b == k).count();
            if n == 0 {
                1.0
            } else {
                2.0 * tp as f64 / n as f64
            }
        })
        .collect()
}

/// Runs a case until the labelling settles, the driver converges or
/// [`MAX_ITERATIONS`]. With `DSC_FIGURES_TRACE` set, every iteration's
/// record is printed to stderr.
///
/// # Panics
/// If the case's parameters are invalid for its image (a bug in the case).
pub fn run(case: &Case) -> Outcome {
    let ph = &case.phantom;
    let image = ImageView::new_2d(ph.width, ph.height, &ph.image).expect("phantom size");
    let t0 = Instant::now();
    let mut s = Segmentation::<D2>::new(image, case.params.clone()).expect("valid case");
    let mut elapsed = t0.elapsed().as_secs_f64();
    let phases = case.params.phases;
    let initial = Snapshot {
        iteration: 0,
        mesh: Mesh::of(s.complex()),
    };
    let initial_topology = Topology::of(&s, phases);
    let npix = ph.width * ph.height;
    let tolerance = (SETTLE_FRACTION * npix as f64).round() as usize;
    // Labellings of the last SETTLE_WINDOW + 1 iterations and their flips.
    let mut window: std::collections::VecDeque<(Vec<u8>, usize)> = Default::default();
    window.push_back((mesh_label_image(&s, &image), 0));
    let (mut snapshots, mut frames) = (Vec::new(), Vec::new());
    let mut converged_at = None;
    let trace = std::env::var_os("DSC_FIGURES_TRACE").is_some();
    while s.history().len() < case.params.max_iterations && !s.converged() {
        let t = Instant::now();
        let rec = s.step();
        elapsed += t.elapsed().as_secs_f64();
        let it = rec.iteration;
        if trace {
            eprintln!(
                "{} it {it}: flips {} max displacement {:.3} L, length {:.0}, means {:?}",
                case.name, rec.flips, rec.max_displacement, rec.length, rec.means
            );
        }
        if case.snapshots.contains(&it) || case.animate {
            let snap = Snapshot {
                iteration: it,
                mesh: Mesh::of(s.complex()),
            };
            if case.snapshots.contains(&it) {
                snapshots.push(snap.clone());
            }
            if case.animate {
                frames.push(snap);
            }
        }
        let labels = mesh_label_image(&s, &image);
        window.push_back((labels, rec.flips));
        if window.len() > SETTLE_WINDOW + 1 {
            window.pop_front();
        }
        if window.len() == SETTLE_WINDOW + 1 {
            let (old, _) = &window[0];
            let (new, _) = &window[SETTLE_WINDOW];
            let changed = old.iter().zip(new).filter(|(a, b)| a != b).count();
            let flips: usize = window.iter().skip(1).map(|w| w.1).sum();
            if changed <= tolerance && flips == 0 {
                converged_at = Some(it - SETTLE_WINDOW);
                break;
            }
        }
    }
    let iterations = s.history().len();
    let driver_converged = s.converged();
    let labels = mesh_label_image(&s, &image);
    let dice_per_phase = dice(&labels, &ph.truth, ph.phases);
    let dice = dice_per_phase.iter().sum::<f64>() / dice_per_phase.len() as f64;
    Outcome {
        initial,
        snapshots,
        frames,
        last: Snapshot {
            iteration: iterations,
            mesh: Mesh::of(s.complex()),
        },
        converged_at: converged_at.unwrap_or(iterations),
        iterations,
        converged: converged_at.is_some() || driver_converged,
        driver_converged,
        dice,
        dice_per_phase,
        seconds: elapsed,
        initial_topology,
        topology: Topology::of(&s, phases),
        edge_length: s.dsc_params().edge_length,
        triangles: s.complex().cell_count(),
    }
}

/// Connected components of each phase of a label image (4-connectivity),
/// e.g. of a ground truth, for comparison with [`Topology::components`].
pub fn pixel_components(labels: &[u8], width: usize, phases: usize) -> Vec<usize> {
    let height = labels.len() / width.max(1);
    let mut seen = vec![false; labels.len()];
    let mut counts = vec![0; phases];
    let mut stack = Vec::new();
    for start in 0..labels.len() {
        if seen[start] {
            continue;
        }
        let l = labels[start];
        counts[l as usize] += 1;
        seen[start] = true;
        stack.push(start);
        while let Some(p) = stack.pop() {
            let (x, y) = (p % width, p / width);
            let mut visit = |q: usize| {
                if !seen[q] && labels[q] == l {
                    seen[q] = true;
                    stack.push(q);
                }
            };
            if x > 0 {
                visit(p - 1);
            }
            if x + 1 < width {
                visit(p + 1);
            }
            if y > 0 {
                visit(p - width);
            }
            if y + 1 < height {
                visit(p + width);
            }
        }
    }
    counts
}
