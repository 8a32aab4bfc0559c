//! The samples of a phase out of the reach of its interfaces' blur: those
//! whose box of [`INTERIOR_RADIUS`] samples each way carries one label.

use super::INTERIOR_RADIUS;

/// Marks a sample that is not interior in [`interior_labels`].
pub(super) const NOT_INTERIOR: u8 = u8::MAX;

/// Per sample of `labels` (on the grid `dims`): its label where every
/// sample within [`INTERIOR_RADIUS`] of it along each axis (a box, cut at
/// the image's border) carries it, else [`NOT_INTERIOR`]. The box is
/// uniform exactly when each line of it is, so one sweep per axis decides
/// it: a few operations per sample.
pub(super) fn interior_labels(labels: &[u8], dims: [usize; 3]) -> Vec<u8> {
    let mut key = labels.to_vec();
    let mut line = Vec::new();
    for axis in 0..3 {
        if dims[axis] > 1 {
            uniform_windows(&mut key, dims, axis, &mut line);
        }
    }
    key
}

/// Along every line of `key` parallel to `axis`, keeps a value whose window
/// of [`INTERIOR_RADIUS`] each way (cut at the ends) holds it alone, and
/// sets the others to [`NOT_INTERIOR`].
fn uniform_windows(key: &mut [u8], dims: [usize; 3], axis: usize, line: &mut Vec<u8>) {
    let r = INTERIOR_RADIUS;
    let step = [1, dims[0], dims[0] * dims[1]][axis];
    let n = dims[axis];
    let mut across = dims;
    across[axis] = 1;
    for c in 0..across[2] {
        for b in 0..across[1] {
            for a in 0..across[0] {
                let start = a + dims[0] * (b + dims[1] * c);
                line.clear();
                line.extend((0..n).map(|k| key[start + k * step]));
                let mut run = 0;
                while run < n {
                    let v = line[run];
                    let end = run + line[run..].iter().take_while(|&&w| w == v).count();
                    for k in run..end {
                        let inside = k.saturating_sub(r) >= run && (k + r).min(n - 1) < end;
                        key[start + k * step] = if inside { v } else { NOT_INTERIOR };
                    }
                    run = end;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interior_samples_are_those_of_a_uniform_box() {
        // a 20 × 12 image: label 1 in a 3-wide column at x = 10..13
        let (w, h) = (20, 12);
        let labels: Vec<u8> = (0..w * h)
            .map(|i| u8::from((10..13).contains(&(i % w))))
            .collect();
        let interior = interior_labels(&labels, [w, h, 1]);
        for i in 0..w * h {
            let x = i % w;
            // the box test, sample by sample
            let (y, r) = (i / w, INTERIOR_RADIUS);
            let uniform = (y.saturating_sub(r)..(y + r + 1).min(h)).all(|yy| {
                (x.saturating_sub(r)..(x + r + 1).min(w)).all(|xx| labels[yy * w + xx] == labels[i])
            });
            let expected = if uniform { labels[i] } else { NOT_INTERIOR };
            assert_eq!(interior[i], expected, "x = {x}, y = {y}");
        }
        assert_eq!(
            interior[5 * w + 2],
            0,
            "3 from the border, 7 from the column"
        );
        assert_eq!(interior[5 * w + 6], 0);
        assert_eq!(interior[5 * w + 7], NOT_INTERIOR);
        assert!(
            (0..w * h).all(|i| interior[i] != 1),
            "the column is too narrow"
        );
    }
}
