//! The thin-structure phantom: detail at and below the mesh's usual edge
//! length, with every structure's own mask so that a result can be scored
//! structure by structure.
//!
//! Widths and radii are in pixels whatever the size (positions scale with
//! `size / 256`): horizontal lines and circular arcs 2, 3 and 4 px wide,
//! disks of radius 2–5 px inside the image and cut by its left border, a
//! ring with a 2-px slit, and a five-pointed star. Two phases, levels 0.3 and
//! 0.7, rendered like the benchmark phantoms (1.5 px blur, noise, 8 bits).

use super::{Phantom2, RenderOptions, TWO_PHASE_LEVELS};

/// One structure of the phantom.
#[derive(Clone, Debug)]
pub struct Structure {
    /// Its name: `line3` (3 px wide), `arc2`, `blob4` (radius 4, inside),
    /// `border5` (radius 5, cut by the border), `slit_ring`, `star`.
    pub name: String,
    /// Its pixels, row-major (`true` inside).
    pub mask: Vec<bool>,
}

/// How a segmentation renders one structure.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureScore {
    /// The structure's name.
    pub name: String,
    /// Fraction of its pixels labelled foreground.
    pub recall: f64,
    /// Connected components (8-connected) of the foreground within its mask.
    pub components: usize,
}

/// Centre of pixel `i` in pixel units.
fn centre(i: usize) -> f64 {
    i as f64 + 0.5
}

/// The structures of the `size × size` phantom (`size` ≥ 128).
pub fn structures(size: usize) -> Vec<Structure> {
    let s = size as f64 / 256.0;
    let mut out = Vec::new();
    let mut add = |name: String, inside: &dyn Fn(f64, f64) -> bool| {
        let mut mask = Vec::with_capacity(size * size);
        for j in 0..size {
            for i in 0..size {
                mask.push(inside(centre(i), centre(j)));
            }
        }
        out.push(Structure { name, mask });
    };
    for (k, w) in [2.0, 3.0, 4.0].into_iter().enumerate() {
        // An odd width is centred on a pixel row, an even one between two
        // rows, so that a line `w` px wide covers exactly `w` rows.
        let y0 = (30.0 + 20.0 * k as f64) * s + if w % 2.0 == 1.0 { 0.5 } else { 0.0 };
        add(format!("line{w}"), &|x, y| {
            (y - y0).abs() < 0.5 * w && x > 20.0 * s && x < 140.0 * s
        });
        let (cx, cy, r0) = (200.0 * s, 60.0 * s, (20.0 + 12.0 * k as f64) * s);
        add(format!("arc{w}"), &|x, y| {
            let r = (x - cx).hypot(y - cy);
            let angle = (y - cy).atan2(x - cx).to_degrees();
            (r - r0).abs() < 0.5 * w && angle.abs() < 150.0
        });
    }
    for (k, r) in [2.0, 3.0, 4.0, 5.0].into_iter().enumerate() {
        let cx = (30.0 + 30.0 * k as f64) * s;
        let cy = 110.0 * s;
        add(format!("blob{r}"), &|x, y| (x - cx).hypot(y - cy) < r);
        let cy = (135.0 + 20.0 * k as f64) * s;
        add(format!("border{r}"), &|x, y| x.hypot(y - cy) < r);
    }
    let (cx, cy) = (100.0 * s, 190.0 * s);
    add("slit_ring".into(), &|x, y| {
        let r = (x - cx).hypot(y - cy);
        r < 30.0 * s && r > 18.0 * s && !((y - cy).abs() < 1.0 && x > cx)
    });
    let star = star_polygon(195.0 * s, 185.0 * s, 40.0 * s, 16.0 * s);
    add("star".into(), &|x, y| inside_polygon(&star, x, y));
    out
}

/// The ten corners of a five-pointed star, the first tip pointing up.
fn star_polygon(cx: f64, cy: f64, outer: f64, inner: f64) -> Vec<(f64, f64)> {
    (0..10)
        .map(|k| {
            let a = (k as f64 * 36.0 - 90.0).to_radians();
            let r = if k % 2 == 0 { outer } else { inner };
            (cx + r * a.cos(), cy + r * a.sin())
        })
        .collect()
}

/// Even-odd crossing test.
fn inside_polygon(poly: &[(f64, f64)], x: f64, y: f64) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let ((xi, yi), (xj, yj)) = (poly[i], poly[j]);
        if (yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Ground truth: 1 on any structure, 0 elsewhere.
pub fn thin_labels(size: usize) -> Vec<u8> {
    let mut out = vec![0u8; size * size];
    for st in structures(size) {
        for (o, &m) in out.iter_mut().zip(&st.mask) {
            *o |= m as u8;
        }
    }
    out
}

/// The thin-structure phantom: [`thin_labels`] with levels (0.3, 0.7),
/// 1.5 px blur, noise, 8-bit quantisation.
pub fn thin(size: usize, noise_sigma: f64, seed: u64) -> Phantom2 {
    let opts = RenderOptions::new(noise_sigma, seed);
    Phantom2::from_labels(size, size, thin_labels(size), &TWO_PHASE_LEVELS, &opts)
}

/// Scores a label image (`size × size`, foreground = `foreground`) structure
/// by structure.
pub fn score(labels: &[u8], size: usize, foreground: u8) -> Vec<StructureScore> {
    structures(size)
        .into_iter()
        .map(|st| {
            let hit: Vec<bool> = st
                .mask
                .iter()
                .zip(labels)
                .map(|(&m, &l)| m && l == foreground)
                .collect();
            let total = st.mask.iter().filter(|&&m| m).count();
            let found = hit.iter().filter(|&&h| h).count();
            StructureScore {
                name: st.name,
                recall: found as f64 / total.max(1) as f64,
                components: components(&hit, size),
            }
        })
        .collect()
}

/// 8-connected components of the `true` pixels.
pub fn components(set: &[bool], size: usize) -> usize {
    let mut seen = vec![false; set.len()];
    let mut stack = Vec::new();
    let mut count = 0;
    for start in 0..set.len() {
        if !set[start] || seen[start] {
            continue;
        }
        count += 1;
        seen[start] = true;
        stack.push(start);
        while let Some(p) = stack.pop() {
            let (i, j) = ((p % size) as isize, (p / size) as isize);
            for dj in -1..=1 {
                for di in -1..=1 {
                    let (x, y) = (i + di, j + dj);
                    if x < 0 || y < 0 || x >= size as isize || y >= size as isize {
                        continue;
                    }
                    let q = y as usize * size + x as usize;
                    if set[q] && !seen[q] {
                        seen[q] = true;
                        stack.push(q);
                    }
                }
            }
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_structure_is_one_component_and_the_truth_scores_perfectly() {
        for size in [256, 512] {
            let truth = thin_labels(size);
            for sc in score(&truth, size, 1) {
                assert_eq!(sc.recall, 1.0, "{} at {size}", sc.name);
                assert_eq!(sc.components, 1, "{} at {size}", sc.name);
            }
            // A line `w` px wide covers `w` pixel rows.
            for st in structures(size)
                .iter()
                .filter(|s| s.name.starts_with("line"))
            {
                let w: usize = st.name["line".len()..].parse().unwrap();
                let rows = (0..size)
                    .filter(|&j| st.mask[j * size..(j + 1) * size].iter().any(|&m| m))
                    .count();
                assert_eq!(rows, w, "{} at {size}", st.name);
            }
            // The slit keeps the ring open: the background is one piece.
            let background: Vec<bool> = truth.iter().map(|&l| l == 0).collect();
            assert_eq!(components(&background, size), 1, "at {size}");
        }
    }
}
