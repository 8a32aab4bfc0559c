//! The paper's evolution as models: thin adapters over [`ForceField`],
//! [`Flipper`] and [`initialise`], whose numerics they do not touch.
//!
//! [`ForceField`]: crate::segment::forces::ForceField

use crate::dim::Point;
use crate::segment::cluster_flips::ClusterFlipper;
use crate::segment::driver::{MAX_BENDING_STEP, MAX_STRETCHING_STEP};
use crate::segment::error::SegmentError;
use crate::segment::flips::Flipper;
use crate::segment::forces::ForceField;
use crate::segment::init::initialise;
use crate::segment::model::{
    ForceContext, ForceTerm, InitContext, Initialiser, LabelContext, LabelRule, LabelView, TermKind,
};
use crate::segment::params::{ForceModel, SegmentParams};
use crate::segment::raster::Raster;

/// Adds a per-vertex field of the [`ForceField`] into `out`.
fn add_field<P: Point>(out: &mut [P], field: &[P]) {
    for (o, f) in out.iter_mut().zip(field) {
        *o += *f;
    }
}

/// The region force of eqs. (5)–(7) (the model chosen by
/// [`SegmentParams::force`]): on a two-phase interface between phases with
/// means `m_i`, `m_j`, the hat-weighted average along the facets of
/// `f(I) = (2I − m_i − m_j)/(m_i − m_j)` times the normal `N_ij` (eq. 6);
/// at triple junctions the mean-bracketing weights of eq. (7).
///
/// Reference magnitude 1 for eq. (6), `(m_0 − m_1)²` for Chan–Vese.
#[derive(Clone, Copy, Debug, Default)]
pub struct RegionForce;

impl<K: Raster> ForceTerm<K> for RegionForce {
    fn name(&self) -> &str {
        "region"
    }

    fn reference_magnitude(&self, ctx: &ForceContext<'_, '_, K>) -> f64 {
        match ctx.params.force {
            ForceModel::Normalised => 1.0,
            ForceModel::ChanVese => {
                let (a, b) = (
                    ctx.phases.mean[0].unwrap_or(0.0),
                    ctx.phases.mean[1].unwrap_or(0.0),
                );
                ((a - b) * (a - b)).max(1e-12)
            }
        }
    }

    fn add_forces(&mut self, ctx: &ForceContext<'_, '_, K>, out: &mut [K::Point]) {
        add_field(out, &ctx.field.external);
    }
}

/// The rigidity term of eq. (2): the bending direction `−Δ²X` traced along
/// each phase boundary, weighted by [`SegmentParams::rigidity`] (β).
#[derive(Clone, Copy, Debug, Default)]
pub struct Rigidity;

impl<K: Raster> ForceTerm<K> for Rigidity {
    fn name(&self) -> &str {
        "rigidity"
    }

    fn kind(&self, params: &SegmentParams) -> TermKind {
        TermKind::Smoothing {
            weight: params.rigidity,
            max_step: MAX_BENDING_STEP,
        }
    }

    fn add_forces(&mut self, ctx: &ForceContext<'_, '_, K>, out: &mut [K::Point]) {
        add_field(out, &ctx.field.bending);
    }

    fn apply_to(
        &mut self,
        field: &mut ForceField<K>,
        input: &[K::Point],
        out: &mut Vec<K::Point>,
    ) -> bool {
        field.apply_bending(input, out);
        true
    }
}

/// The elasticity term of eq. (2): the umbrella `ΔX` along each phase
/// boundary, weighted by [`SegmentParams::elasticity`] (α, 0 by default).
#[derive(Clone, Copy, Debug, Default)]
pub struct Elasticity;

impl<K: Raster> ForceTerm<K> for Elasticity {
    fn name(&self) -> &str {
        "elasticity"
    }

    fn kind(&self, params: &SegmentParams) -> TermKind {
        TermKind::Smoothing {
            weight: params.elasticity,
            max_step: MAX_STRETCHING_STEP,
        }
    }

    fn add_forces(&mut self, ctx: &ForceContext<'_, '_, K>, out: &mut [K::Point]) {
        add_field(out, &ctx.field.stretching);
    }

    fn apply_to(
        &mut self,
        field: &mut ForceField<K>,
        input: &[K::Point],
        out: &mut Vec<K::Point>,
    ) -> bool {
        field.apply_umbrella(input, out);
        true
    }
}

/// The paper's cell flips (section III.C): two phases, a cell flips when its
/// mean is nearer the other phase's mean; more phases, to the phase most of
/// its pixels are nearest. With [`SegmentParams::flip_guard`] a flip must also
/// lower the Mumford–Shah energy (see [`crate::segment::flips`]).
#[derive(Clone, Debug, Default)]
pub struct CellFlips {
    flipper: Flipper,
}

impl<K: Raster> LabelRule<K> for CellFlips {
    fn name(&self) -> &str {
        "cell flips"
    }

    fn relabel(&mut self, ctx: &mut LabelContext<'_, '_, K>) -> usize {
        self.flipper.flip(
            ctx.complex,
            ctx.image,
            ctx.cells,
            ctx.phases,
            ctx.length_weight,
            ctx.params.flip_guard,
            ctx.params.flip_once,
        )
    }

    fn would_relabel(&mut self, view: &LabelView<'_, '_, K>) -> Option<bool> {
        Some(self.flipper.would_flip(
            view.complex,
            view.image,
            view.cells,
            view.phases,
            view.length_weight,
            view.params.flip_guard,
            view.params.flip_once,
        ))
    }
}

/// Whole-region flips (with [`SegmentParams::flip_guard`] only): every
/// connected same-phase region is relabelled to the neighbouring phase that
/// lowers the Mumford–Shah energy most, if any does. With adaptive
/// resolution, connected groups of cells that all fit another phase are
/// then relabelled together when that lowers the energy
/// ([`crate::segment::cluster_flips`]): refined cells over a thin line are
/// too small to flip one by one.
#[derive(Clone, Debug, Default)]
pub struct ComponentFlips {
    flipper: Flipper,
    clusters: ClusterFlipper,
}

impl<K: Raster> LabelRule<K> for ComponentFlips {
    fn name(&self) -> &str {
        "component flips"
    }

    fn relabel(&mut self, ctx: &mut LabelContext<'_, '_, K>) -> usize {
        if !ctx.params.flip_guard {
            return 0;
        }
        let nu = ctx.length_weight;
        let mut flips = self
            .flipper
            .component_flips(ctx.complex, ctx.cells, ctx.phases, nu);
        if ctx.params.sizing.adaptive {
            flips += self.clusters.flip(ctx.complex, ctx.cells, ctx.phases, nu);
        }
        flips
    }

    fn would_relabel(&mut self, view: &LabelView<'_, '_, K>) -> Option<bool> {
        let nu = view.length_weight;
        Some(
            view.params.flip_guard
                && (self
                    .flipper
                    .would_flip_components(view.complex, view.cells, view.phases, nu)
                    || (view.params.sizing.adaptive
                        && self
                            .clusters
                            .would_flip(view.complex, view.cells, view.phases, nu))),
        )
    }
}

/// The initialisation chosen by [`SegmentParams::init`] (range, disks or a
/// label image).
#[derive(Clone, Copy, Debug, Default)]
pub struct ParamsInit;

impl<K: Raster> Initialiser<K> for ParamsInit {
    fn initialise(
        &mut self,
        ctx: &mut InitContext<'_, '_, K>,
    ) -> Result<Vec<Option<f64>>, SegmentError> {
        initialise(
            ctx.complex,
            ctx.image,
            ctx.params,
            ctx.cells,
            ctx.range,
            ctx.classes,
        )
    }
}
