//! dsc-seg: multiphase image segmentation with the deformable simplicial
//! complex (DSC), generic over dimension, and a framework for deformable
//! models on it.
//!
//! # The method
//!
//! The DSC covers the image domain with a triangle mesh (2D) or a
//! tetrahedral mesh (3D) whose cells carry phase labels `0..N`. The
//! segmentation is the labelling; its *interface*, the facets between cells
//! of different phases, is an explicit curve network (surface network in 3D).
//! The evolution follows the deformable-model equation (1) of the paper,
//! `∂X/∂t = F_ext(X) + F_int(X)`, on the interface vertices `X`:
//!
//! 1. **Integrate** the image over every cell (each pixel counted exactly once)
//!    and compute each phase's mean `m_i`.
//! 2. **Flip labels**: a cell whose pixels fit another phase better changes
//!    label (section III.C; with the default guard only if that lowers the
//!    piecewise-constant Mumford–Shah energy `Σ(I − m)² + ν·length`).
//! 3. **Compute forces** per interface vertex: the region force of eq. (6),
//!    `f(I) = (2I − m_i − m_j)/(m_i − m_j)` along the normal `N_ij`, averaged
//!    along the facets; the junction force of eq. (7) at triple junctions; the
//!    rigidity term of eq. (2) (`−β Δ²X`) to keep the interface smooth.
//! 4. **Deform**: move every vertex towards `X + Δt·F` as far as it can go
//!    without inverting a cell, improve the mesh around the movers (flips,
//!    smoothing, collapses and splits), and repeat. Merging, splitting and
//!    vanishing regions and any number of phases with triple junctions come
//!    from these mesh operations; nothing in the forces knows about topology.
//! 5. **Stop** when nothing flips and nothing moves more than a small
//!    fraction of the average edge length `L` for a few iterations.
//!
//! `L` is the method's single resolution parameter (see
//! [`segment::default_edge_length`]); every threshold of the DSC and of the
//! segmentation is derived from it ([`dsc::DscParams`],
//! [`segment::SegmentParams`]).
//!
//! # A first segmentation
//!
//! A 2D two-phase segmentation of a small image, the paper's pipeline with its
//! defaults ([`segment::Segmentation::new`]):
//!
//! ```
//! use dsc_seg::segment::{ImageView, SegmentParams, Segmentation2};
//!
//! // A 32 × 32 image: a bright square on a dark background.
//! let (w, h) = (32, 32);
//! let pixels: Vec<f32> = (0..w * h)
//!     .map(|i| {
//!         let (x, y) = (i % w, i / w);
//!         if (8..24).contains(&x) && (10..22).contains(&y) { 0.8 } else { 0.2 }
//!     })
//!     .collect();
//! let image = ImageView::new_2d(w, h, &pixels).unwrap();
//!
//! let mut params = SegmentParams::new(2);
//! params.max_iterations = 20;
//! let mut seg = Segmentation2::new(image, params)?;
//! let report = seg.run(|record| assert!(record.energy.is_finite()));
//!
//! // One label per pixel, phases ordered by increasing mean.
//! let labels = seg.label_image();
//! assert_eq!(labels[16 * w + 16], 1); // inside the square
//! assert_eq!(labels[2 * w + 2], 0); // background
//! assert!(report.iterations <= 20);
//! # Ok::<(), dsc_seg::segment::SegmentError>(())
//! ```
//!
//! # Extending it: forces, label rules, initialisations
//!
//! The evolution is data: a [`segment::Models`] value holding
//! [`segment::ForceTerm`]s, [`segment::LabelRule`]s and an
//! [`segment::Initialiser`], all generic over the dimension. The paper's own
//! terms are written against these traits ([`segment::models::paper`]);
//! [`segment::Segmentation::with_models`] runs any combination, and
//! [`segment::Segmentation::run_until`] hands every iteration's record and
//! the segmentation itself to an observer that can record frames, change
//! parameters or models mid-run, and decide when to stop.
//!
//! ```
//! use dsc_seg::segment::models::Volcano;
//! use dsc_seg::segment::{Flow, ImageView, Models2, SegmentParams, Segmentation2};
//! use nalgebra::Vector2;
//!
//! # let (w, h) = (32, 32);
//! # let pixels: Vec<f32> = (0..w * h)
//! #     .map(|i| if (8..24).contains(&(i % w)) && (10..22).contains(&(i / w)) { 0.8 } else { 0.2 })
//! #     .collect();
//! # let image = ImageView::new_2d(w, h, &pixels).unwrap();
//! // The paper's evolution plus a user's repelling point, switched off for now.
//! let params = SegmentParams::new(2);
//! let models = Models2::paper(&params).with_force(Volcano::new(Vector2::new(26.0, 16.0), 0.0, 4.0));
//! let mut seg = Segmentation2::with_models(image, params, models)?;
//! let mut frames = Vec::new();
//! seg.run_until(|s, record| {
//!     frames.push(s.label_image()); // a snapshot per iteration
//!     if record.iteration == 5 {
//!         // the user steps in
//!         s.force_mut::<Volcano<Vector2<f64>>>().unwrap().strength = 2.0;
//!     }
//!     // a custom stopping rule: a fixed budget
//!     if record.iteration >= 8 { Flow::Stop } else { Flow::Continue }
//! });
//! assert_eq!(frames.len(), 8);
//! # Ok::<(), dsc_seg::segment::SegmentError>(())
//! ```
//!
//! The `examples/` directory shows three classical forces from the
//! deformable-model literature on built-in phantoms, each with a picture in
//! `out/` and a test: a balloon ([`segment::models::Balloon`],
//! `examples/balloon.rs`), the snake's edge force
//! ([`segment::models::EdgeAttraction`], `examples/edge_snake.rs`) and a
//! user's volcano ([`segment::models::Volcano`], `examples/volcano.rs`).
//!
//! # Dimensions
//!
//! Everything is written once against the sealed [`dim::Dim`] trait,
//! implemented by [`dim::D2`] (triangles over pixels) and [`dim::D3`]
//! (tetrahedra over voxels). The aliases name the two cases:
//!
//! | | 2D | 3D |
//! |---|---|---|
//! | complex | [`complex::Complex2`] = `Complex<D2>` | [`complex::Complex3`] = `Complex<D3>` |
//! | segmentation | [`segment::Segmentation2`] = `Segmentation<'_, D2>` | [`segment::Segmentation3`] = `Segmentation<'_, D3>` |
//! | models | [`segment::Models2`] = `Models<D2>` | [`segment::Models3`] = `Models<D3>` |
//!
//! The segmentation needs only [`segment::Raster`] from a dimension (which
//! pixels a cell covers, facet sampling, interpolation): scanline spans over
//! pixels in 2D, exact voxel-centre ownership of tetrahedra in 3D.
//!
//! # Layers
//!
//! [`dim`] → [`complex`] (connectivity, labels, validation) → [`ops`] (local
//! mesh operations) → [`dsc`] (the deform loop) → [`segment`] (image
//! statistics, forces, label flips, the driver); [`io`] and [`phantom`]
//! beside them, [`pipeline`] and the `dsc-seg` binary on top.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]

pub mod batch;
#[doc(hidden)]
pub mod bench;
pub mod cancel;
pub mod complex;
pub mod dim;
pub mod dsc;
pub mod error;
pub mod figures;
pub mod ids;
pub mod io;
pub mod ops;
pub mod options;
pub mod phantom;
pub mod pipeline;
pub mod segment;
pub mod segmented;
pub mod staging;

pub use error::{Error, Result};
