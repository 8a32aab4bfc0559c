//! The three example forces (balloon, edge attraction, volcano):
//! each test runs the example's own scenario and asserts its outcome.

use dsc_seg::pipeline::mean_dice;
use dsc_seg::segment::StopReason;

#[allow(dead_code)]
#[path = "../../examples/balloon.rs"]
mod balloon;
#[allow(dead_code)]
#[path = "../../examples/edge_snake.rs"]
mod edge_snake;
#[allow(dead_code)]
#[path = "../../examples/volcano.rs"]
mod volcano;

/// A seed disk in the trunk inflates, splits around the ring's hole, merges
/// at the top and stops at the object's edges.
#[test]
fn balloon_inflates_a_seed_to_the_object() {
    let n = 128;
    let o = balloon::scenario(n, None).unwrap();
    let ph = &o.phantom;
    let seed = mean_dice(&o.initial, &ph.truth, 2);
    let dice = mean_dice(&o.labels, &ph.truth, 2);
    assert!(seed < 0.6, "seed Dice {seed}");
    assert!(dice > 0.97, "final Dice {dice}");
    assert_eq!(o.report.stop_reason, StopReason::Converged);
    assert_eq!(o.components, 1, "the branches merged into one region");
    // the ring's hole stays background: the balloon did not leak through the edge
    let hole = (0.40 * n as f64) as usize * n + n / 2;
    assert_eq!(o.labels[hole], 0);
    let area = |l: &[u8]| l.iter().filter(|&&v| v == 1).count();
    assert!(area(&o.labels) > 5 * area(&o.initial));
}

/// An outline 3 px too large snaps onto the edges of every shape.
#[test]
fn edge_force_pulls_the_outline_onto_the_edges() {
    let o = edge_snake::scenario(256, None).unwrap();
    let ph = &o.phantom;
    let before = mean_dice(&o.initial, &ph.truth, 2);
    let after = mean_dice(&o.labels, &ph.truth, 2);
    assert!(before < 0.92, "initial Dice {before}");
    assert!(after > 0.985, "final Dice {after}");
    assert_eq!(o.report.stop_reason, StopReason::Converged);
}

/// After convergence, a volcano outside the ring dents it locally and leaves
/// the rest of the segmentation alone.
#[test]
fn volcano_dents_the_interface_near_it_only() {
    let n = 128;
    let o = volcano::scenario(n, None).unwrap();
    assert!(
        o.erupted_at > 0,
        "the pipeline converged before the eruption"
    );
    assert_eq!(o.report.stop_reason, StopReason::Converged);
    assert!(o.report.iterations > o.erupted_at);
    let (cx, cy) = o.centre;
    let at = |x: f64, y: f64| y as usize * n + x as usize;
    // 3 px inside the ring's edge (5 px from the volcano) on the volcano's
    // axis: object before, background after (measured: the dent is ~5 px deep)
    let p = at(cx - 8.0, cy);
    assert_eq!(o.before[p], 1, "object before the eruption");
    assert_eq!(o.after[p], 0, "dented by the volcano");
    // far from the volcano (beyond 3ρ = 24 px) only the noise-level jitter
    // of a further relaxation (flips off): under 1% of the object's area
    let far = |i: usize| {
        let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
        (x - cx).hypot(y - cy) > 24.0
    };
    let changed = |i: &usize| o.before[*i] != o.after[*i];
    let far_changes = (0..n * n).filter(|&i| far(i)).filter(changed).count();
    let near_changes = (0..n * n).filter(|&i| !far(i)).filter(changed).count();
    let object = o.before.iter().filter(|&&v| v == 1).count();
    eprintln!("volcano: {near_changes} pixels changed near, {far_changes} far, object {object}");
    assert!(
        100 * far_changes < object,
        "{far_changes} pixels changed far away"
    );
    assert!(near_changes >= 40, "a dent of {near_changes} pixels");
    let ph = &o.phantom;
    assert!(mean_dice(&o.before, &ph.truth, 2) > 0.97);
}

/// The segmentation loop with user-supplied pieces: a closure initialiser, a
/// custom label rule, a custom stopping rule, parameters changed mid-run.
#[test]
fn custom_models_and_observer_drive_the_same_loop() {
    use dsc_seg::complex::Complex2;
    use dsc_seg::dim::D2;
    use dsc_seg::segment::{
        Flow, ImageView, IterationState, LabelRule, Models, SegmentError, SegmentParams,
        Segmentation,
    };

    /// Relabels nothing but counts its calls.
    struct Count(usize);
    impl LabelRule<D2> for Count {
        fn name(&self) -> &str {
            "count"
        }
        fn relabel(&mut self, _: &mut Complex2, _: &IterationState<'_, '_>) -> usize {
            self.0 += 1;
            0
        }
    }

    let (w, h) = (24, 24);
    let pixels: Vec<f32> = (0..w * h)
        .map(|i| if i % w < w / 2 { 0.2 } else { 0.8 })
        .collect();
    let image = ImageView::new_2d(w, h, &pixels).unwrap();
    let right_half = |complex: &mut Complex2, state: &IterationState<'_, '_>| {
        let mut changes = Vec::new();
        for c in complex.cell_ids() {
            let p = complex.cell_points(c);
            let x = (p[0].x + p[1].x + p[2].x) / 3.0;
            changes.push((c, u32::from(x > 12.0)));
        }
        complex.set_labels(&changes);
        Ok::<_, SegmentError>(vec![None; state.params.phases])
    };
    let models = Models::empty().with_init(right_half).with_rule(Count(0));
    let mut seg = Segmentation::<D2>::with_models(image, SegmentParams::new(2), models).unwrap();
    let start = seg.label_image();
    let report = seg.run_until(|s, rec| {
        if rec.iteration == 2 {
            s.params_mut().label_flips = false;
        }
        if rec.iteration == 4 {
            Flow::Stop
        } else {
            Flow::Continue
        }
    });
    assert_eq!(report.iterations, 4);
    assert_eq!(report.stop_reason, StopReason::Stopped);
    // no force: nothing moved; the rule ran while flips were on (iterations 1, 2)
    assert_eq!(seg.label_image(), start);
    assert_eq!(seg.models_mut().rule_mut::<Count>().unwrap().0, 2);
    assert!(report.history.iter().all(|r| r.max_displacement == 0.0));

    // an initialiser that produces a label beyond the phases is an error
    let bad = |complex: &mut Complex2, _: &IterationState<'_, '_>| {
        let c = complex.cell_ids().next().unwrap();
        complex.set_label(c, 5);
        Ok::<_, SegmentError>(Vec::new())
    };
    let params = SegmentParams::new(2);
    let err = Segmentation::<D2>::with_models(
        image,
        params.clone(),
        Models::paper(&params).with_init(bad),
    );
    assert!(matches!(err, Err(SegmentError::Init(_))));
}

/// The facet-integrated route reproduces the paper's region force (eq. 6)
/// and points like the balloon's vertex normals for a constant pressure.
#[test]
fn facet_integrated_forces_match_the_region_force_and_the_normals() {
    use dsc_seg::complex::Complex2;
    use dsc_seg::dim::{Point, D2};
    use dsc_seg::segment::models::{PaperField, RegionForce};
    use dsc_seg::segment::{
        phase_normals, ForceTerm, ImageView, IterationState, Models, Raster, SegmentParams,
        Segmentation,
    };
    use nalgebra::Vector2;
    use std::sync::{Arc, Mutex};

    type Seen = Arc<Mutex<Vec<(f64, f64)>>>;
    /// Compares, at every two-phase interface vertex, eq. (6) integrated
    /// here with the paper's region force, and a unit pressure with the normals.
    struct Probe(Seen, PaperField<D2>);
    impl ForceTerm<D2> for Probe {
        fn name(&self) -> &str {
            "probe"
        }
        fn add_forces(
            &mut self,
            complex: &Complex2,
            state: &IterationState<'_, '_>,
            _out: &mut [Vector2<f64>],
        ) {
            let nv = complex.vertex_capacity();
            let (mut eq6, mut push) = (vec![Vector2::zeros(); nv], vec![Vector2::zeros(); nv]);
            let mut scratch = Vec::new();
            let img = state.image;
            let ph = state.phases;
            state.add_facet_integrated(
                complex,
                |p, a, b| {
                    let (ma, mb) = (ph.mean_of(a).unwrap(), ph.mean_of(b).unwrap());
                    (2.0 * D2::sample(img, p) - ma - mb) / (ma - mb)
                },
                &mut scratch,
                &mut eq6,
            );
            state.add_facet_integrated(
                complex,
                |_, a, _| if a == 1 { 1.0 } else { -1.0 },
                &mut scratch,
                &mut push,
            );
            let mut normals = Vec::new();
            phase_normals(complex, 1, &mut normals);
            let mut seen = self.0.lock().unwrap();
            // the region force, computed for this evaluation by the term before
            assert_eq!(self.1.computed_for(), Some(state.evaluation));
            let field = self.1.field();
            for v in complex.vertex_ids() {
                let k = complex.class(v);
                if k.kind != dsc_seg::complex::VertexKind::Interface || k.on_boundary() {
                    continue;
                }
                let i = v.index();
                let region = field.external[i];
                seen.push((
                    (eq6[i] - region).length() / region.length().max(1e-9),
                    push[i].dot(&normals[i]) / push[i].length().max(1e-12),
                ));
            }
        }
    }

    let (w, h) = (40, 40);
    let pixels: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 - 19.5, (i / w) as f64 - 19.5);
            if x.hypot(y) < 11.0 {
                0.8
            } else {
                0.2
            }
        })
        .collect();
    let image = ImageView::new_2d(w, h, &pixels).unwrap();
    let seen: Seen = Arc::default();
    let params = SegmentParams::new(2);
    let mut models = Models::paper(&params);
    let field = models
        .force_mut::<RegionForce<D2>>()
        .unwrap()
        .field()
        .clone();
    let models = models.with_force(Probe(seen.clone(), field));
    let mut seg = Segmentation::<D2>::with_models(image, params, models).unwrap();
    seg.step();
    seg.step();
    let seen = seen.lock().unwrap();
    assert!(seen.len() > 20);
    for &(rel, cos) in seen.iter() {
        assert!(
            rel < 1e-9,
            "eq. 6 integrated differs from the region force by {rel}"
        );
        assert!(cos > 0.9, "pressure direction vs normal: cos {cos}");
    }
}
