//! The image samples of the interface facets, remembered from one force
//! evaluation to the next.
//!
//! A facet's samples are a function of its corner positions, the sample
//! spacing and the image alone: a facet whose corners did not move since
//! the last evaluation has the same samples to the bit. Once the
//! interfaces settle most corners stay where they are (a vertex moves only
//! when its step is at least the smallest move), and interpolating the
//! image was most of the forces' work, paid again on every evaluation; an
//! evaluation repeated on an unchanged mesh (a settle round, a flip round
//! that flipped nothing) takes them all from here.
//!
//! Only the intensities are kept (one `f64` per sample); the quadrature's
//! weights are recomputed from the positions, as cheap as reading them.

use super::image::ImageView;
use crate::complex::InterfaceFacet;
use crate::dim::{Dim, Point};

/// Where a facet's intensities lie in an evaluation's store, with the
/// corner positions they were taken at.
#[derive(Clone, Copy, Debug)]
struct Entry<P> {
    points: [P; 3],
    start: usize,
    len: usize,
}

/// What the samples depend on besides the facet: the image (its address,
/// extent and voxel size) and the spacing.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Source {
    data: usize,
    dims: [usize; 3],
    spacing: [u64; 3],
    sample_spacing: u64,
}

impl Source {
    fn of(image: &ImageView<'_>, sample_spacing: f64) -> Self {
        Source {
            data: image.data.as_ptr() as usize,
            dims: image.dims,
            spacing: image.spacing.map(f64::to_bits),
            sample_spacing: sample_spacing.to_bits(),
        }
    }
}

/// The facets' intensities of the last evaluation, looked up by the facet's
/// cell and opposite corner and valid where the corners are bit for bit
/// where they were.
#[derive(Clone, Debug)]
pub(crate) struct SampleMemo<P> {
    /// Per cell id and local facet index: the round that stored its entry
    /// and the entry's index in that round's list.
    slots: Vec<(u32, u32)>,
    /// The entries and intensities of the last evaluation, read by lookups.
    last: Store<P>,
    /// Those of the evaluation being run, written by `record`.
    current: Store<P>,
    /// The rounds of lookups since the last reset, the current one last
    /// (slots stored in round `round − 1` point into `last`).
    round: u32,
    /// The driver's count of the evaluation being run.
    evaluation: Option<u64>,
    source: Option<Source>,
}

/// One evaluation's facets and their intensities.
#[derive(Clone, Debug)]
struct Store<P> {
    entries: Vec<Entry<P>>,
    intensities: Vec<f64>,
}

impl<P> Default for Store<P> {
    fn default() -> Self {
        Store {
            entries: Vec::new(),
            intensities: Vec::new(),
        }
    }
}

impl<P> Default for SampleMemo<P> {
    fn default() -> Self {
        SampleMemo {
            slots: Vec::new(),
            last: Store::default(),
            current: Store::default(),
            round: 0,
            evaluation: None,
            source: None,
        }
    }
}

impl<P: Point> SampleMemo<P> {
    /// Starts force evaluation `evaluation` (the driver's count) of a
    /// complex of `cells` cell ids sampling `image` every `sample_spacing`:
    /// the last evaluation's intensities become the ones looked up, none
    /// if it was not evaluation `evaluation − 1` or sampled another image
    /// or spacing.
    pub fn begin<K: Dim<Point = P>>(
        &mut self,
        evaluation: u64,
        cells: usize,
        image: &ImageView<'_>,
        sample_spacing: f64,
    ) {
        let source = Source::of(image, sample_spacing);
        let follows = self
            .evaluation
            .is_some_and(|e| e.checked_add(1) == Some(evaluation));
        if !follows || self.source != Some(source) || self.round == u32::MAX {
            self.slots.clear();
            self.round = 1;
            self.source = Some(source);
        }
        self.evaluation = Some(evaluation);
        // (a slot of round 0, new, is never valid: the rounds after a reset
        // count from 2)
        self.slots.resize(cells * K::NV, (0, 0));
        std::mem::swap(&mut self.last, &mut self.current);
        self.current.entries.clear();
        self.current.intensities.clear();
        self.round += 1;
    }

    /// Forgets every facet's intensities (the image sampled changed).
    pub fn forget(&mut self) {
        self.evaluation = None;
    }

    /// The intensities the last evaluation took on `facet`, if its corners
    /// have not moved since.
    pub fn lookup<K: Dim<Point = P>>(&self, facet: &InterfaceFacet<P>) -> Option<&[f64]> {
        let &(round, index) = self.slots.get(slot::<K>(facet))?;
        if round + 1 != self.round {
            return None;
        }
        let entry = self.last.entries.get(index as usize)?;
        let unmoved = (0..K::N).all(|c| same_bits::<K>(entry.points[c], facet.points[c]));
        unmoved
            .then(|| {
                self.last
                    .intensities
                    .get(entry.start..entry.start + entry.len)
            })
            .flatten()
    }

    /// Stores the intensities this evaluation took on `facet`.
    pub fn record<K: Dim<Point = P>>(
        &mut self,
        facet: &InterfaceFacet<P>,
        intensities: impl Iterator<Item = f64>,
    ) {
        let (Some(slot), Ok(index)) = (
            self.slots.get_mut(slot::<K>(facet)),
            u32::try_from(self.current.entries.len()),
        ) else {
            return;
        };
        *slot = (self.round, index);
        let start = self.current.intensities.len();
        self.current.intensities.extend(intensities);
        self.current.entries.push(Entry {
            points: facet.points,
            start,
            len: self.current.intensities.len() - start,
        });
    }
}

/// The entry index of `facet`: its cell's, then its opposite corner.
fn slot<K: Dim>(facet: &InterfaceFacet<K::Point>) -> usize {
    facet.cell.index() * K::NV + facet.opposite
}

/// Whether `a` and `b` have the same coordinates to the bit.
fn same_bits<K: Dim>(a: K::Point, b: K::Point) -> bool {
    (0..K::N).all(|i| a[i].to_bits() == b[i].to_bits())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::complex::{CellId, Complex, VertexId};
    use crate::dim::D3;
    use nalgebra::Vector3;

    /// A facet of cell 5 (opposite its corner 2) at `points`.
    fn facet(points: [Vector3<f64>; 3]) -> InterfaceFacet<Vector3<f64>> {
        InterfaceFacet {
            cell: CellId(5),
            opposite: 2,
            a: 0,
            b: 1,
            corners: [VertexId(0), VertexId(1), VertexId(2)],
            points,
            normal: Vector3::z(),
            measure: 0.5,
        }
    }

    #[test]
    fn a_facet_finds_the_last_evaluations_intensities_while_its_corners_stay() {
        let data = vec![0.5f32; 8 * 8 * 8];
        let image = ImageView::new_3d([8, 8, 8], &data).unwrap();
        let points = [Vector3::zeros(), Vector3::x(), Vector3::y()];
        let moved = [points[0], points[1], Vector3::new(0.0, 1.0, 1e-12)];
        let mut memo = SampleMemo::default();
        memo.begin::<D3>(1, 10, &image, 1.0);
        assert_eq!(
            memo.lookup::<D3>(&facet(points)),
            None,
            "nothing stored yet"
        );
        memo.record::<D3>(&facet(points), [0.25, 0.75].into_iter());
        memo.begin::<D3>(2, 10, &image, 1.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), Some(&[0.25, 0.75][..]));
        assert_eq!(memo.lookup::<D3>(&facet(moved)), None, "a corner moved");
        // not recorded in evaluation 2: gone in evaluation 3
        memo.begin::<D3>(3, 10, &image, 1.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), None);
        memo.record::<D3>(&facet(points), [0.5].into_iter());
        // an evaluation skipped, another spacing, another image: forgotten
        memo.begin::<D3>(5, 10, &image, 1.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), None);
        memo.record::<D3>(&facet(points), [0.5].into_iter());
        memo.begin::<D3>(6, 10, &image, 2.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), None);
        memo.record::<D3>(&facet(points), [0.5].into_iter());
        let other = vec![0.5f32; 8 * 8 * 8];
        let other = ImageView::new_3d([8, 8, 8], &other).unwrap();
        memo.begin::<D3>(7, 10, &other, 2.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), None);
        memo.record::<D3>(&facet(points), [0.5].into_iter());
        memo.forget();
        memo.begin::<D3>(8, 10, &other, 2.0);
        assert_eq!(memo.lookup::<D3>(&facet(points)), None);
    }

    #[test]
    fn a_complex_that_did_not_move_takes_every_sample_from_the_memo() {
        let complex = Complex::<D3>::cuboid([6.0; 3], 2.0).unwrap();
        let data = vec![0.5f32; 6 * 6 * 6];
        let image = ImageView::new_3d([6, 6, 6], &data).unwrap();
        let facets: Vec<_> = complex
            .cell_ids()
            .flat_map(|c| (0..4).map(move |i| (c, i)))
            .map(|(c, i)| {
                let mut f = facet([Vector3::zeros(); 3]);
                f.cell = c;
                f.opposite = i;
                let pts = complex.cell_points(c);
                let mut k = 0;
                for (j, p) in pts.iter().enumerate() {
                    if j != i {
                        f.points[k] = *p;
                        k += 1;
                    }
                }
                f
            })
            .collect();
        let mut memo = SampleMemo::default();
        memo.begin::<D3>(1, complex.cell_capacity(), &image, 1.0);
        for (n, f) in facets.iter().enumerate() {
            memo.record::<D3>(f, [n as f64, 0.5].into_iter());
        }
        memo.begin::<D3>(2, complex.cell_capacity(), &image, 1.0);
        for (n, f) in facets.iter().enumerate() {
            assert_eq!(memo.lookup::<D3>(f), Some(&[n as f64, 0.5][..]));
        }
    }
}
