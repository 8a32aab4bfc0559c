//! Samples of given ranks among many `f32` samples, in two counting passes.
//!
//! The robust range and the noise estimate of [`intensity`](super::intensity)
//! are order statistics of every pixel or voxel (up to a million of them). A
//! selection among all the samples copies them into one array and reorders
//! it, several times its length in comparisons and swaps. Here the samples
//! are read as integer order keys ([`order_key`]), counted by their top 16
//! bits, and only the keys of the one bucket holding each wanted rank are
//! copied and selected among: the same samples, bit for bit, at the cost of
//! two reads of the samples.

/// Number of buckets: one per value of a key's top 16 bits.
const BUCKETS: usize = 1 << 16;

/// An integer that orders as [`f32::total_cmp`] orders `v` (its own
/// transformation of the bits): selecting among integers is faster than
/// among floats through a comparison function. [`from_order_key`] undoes it.
pub(super) fn order_key(v: f32) -> i32 {
    let bits = v.to_bits() as i32;
    bits ^ (((bits >> 31) as u32) >> 1) as i32
}

/// The sample whose [`order_key`] is `key`.
pub(super) fn from_order_key(key: i32) -> f32 {
    // The transformation keeps the sign bit, so it is its own inverse.
    f32::from_bits(order_key(f32::from_bits(key as u32)) as u32)
}

/// The bucket of `key`: its top 16 bits, numbered so that buckets follow
/// the keys' order (the sign bit flipped).
fn bucket(key: i32) -> usize {
    (((key as u32) ^ 0x8000_0000) >> 16) as usize
}

/// The samples of the ranks `ranks_among(n)` gives for the number `n` of
/// samples (0 = the smallest, in [`f32::total_cmp`]'s order; every rank
/// below `n`) among those `samples()` yields, as [`order_key`]s; `None`
/// for no samples. `samples` is called once per pass and must yield the
/// same samples each time.
pub(super) fn keys_of_ranks<const R: usize, I>(
    samples: impl Fn() -> I,
    ranks_among: impl FnOnce(usize) -> [usize; R],
) -> Option<[i32; R]>
where
    I: Iterator<Item = f32>,
{
    // (an array of the buckets' own length: indexing it needs no bounds check)
    let mut counts: Box<[u32; BUCKETS]> = vec![0u32; BUCKETS]
        .into_boxed_slice()
        .try_into()
        .expect("BUCKETS counts");
    // (`for_each` rather than a `for` loop: a chain of adapters, such as
    // the rows of pairs of the noise estimate, then runs as nested loops
    // instead of one `next` call per sample)
    let mut n = 0usize;
    samples().for_each(|v| {
        counts[bucket(order_key(v))] += 1;
        n += 1;
    });
    if n == 0 {
        return None;
    }
    let ranks = ranks_among(n);
    let places = places_of_ranks(&counts[..], ranks);
    // Each wanted bucket's keys, gathered once (two ranks may share one).
    let mut gathered: [Vec<i32>; R] = std::array::from_fn(|_| Vec::new());
    let owner = |i: usize| (0..=i).find(|&j| places[j].0 == places[i].0).unwrap_or(i);
    samples().for_each(|v| {
        let key = order_key(v);
        let b = bucket(key);
        if let Some(i) = (0..R).find(|&i| places[i].0 == b) {
            gathered[i].push(key);
        }
    });
    Some(std::array::from_fn(|i| {
        let keys = &mut gathered[owner(i)];
        *keys.select_nth_unstable(places[i].1).1
    }))
}

/// For each of `ranks`, the bucket holding the key of that rank and the
/// key's rank within the bucket, from the buckets' counts.
fn places_of_ranks<const R: usize>(counts: &[u32], ranks: [usize; R]) -> [(usize, usize); R] {
    ranks.map(|rank| place_of_rank(counts, rank))
}

/// Buckets counted at a time by [`place_of_rank`].
const BLOCK: usize = 256;

/// The bucket holding the key of rank `rank` and the key's rank within the
/// bucket: the counts are summed a block at a time (a loop the compiler
/// vectorises), and only the block holding the rank bucket by bucket.
fn place_of_rank(counts: &[u32], rank: usize) -> (usize, usize) {
    let mut below = 0usize;
    for (k, block) in counts.chunks(BLOCK).enumerate() {
        let in_block: usize = block.iter().map(|&c| c as usize).sum();
        if rank < below + in_block {
            for (j, &c) in block.iter().enumerate() {
                if rank < below + c as usize {
                    return (k * BLOCK + j, rank - below);
                }
                below += c as usize;
            }
        }
        below += in_block;
    }
    panic!("rank {rank} beyond the {below} samples");
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The keys of the ranks are those of the samples sorted by
        /// `f32::total_cmp`, bit for bit (negative zeros, infinities, and
        /// many equal samples included), for ranks in one bucket or two.
        #[test]
        fn keys_of_ranks_are_the_sorted_samples(
            data in prop::collection::vec(
                prop_oneof![
                    -1e6f32..1e6,
                    0.0f32..1.0,
                    Just(0.25f32),
                    Just(0.0f32),
                    Just(-0.0f32),
                    Just(f32::INFINITY),
                    Just(f32::NEG_INFINITY),
                ],
                1..400,
            ),
            a in 0.0f64..1.0,
            b in 0.0f64..1.0,
        ) {
            let mut sorted = data.clone();
            sorted.sort_by(f32::total_cmp);
            let rank = |q: f64| ((data.len() - 1) as f64 * q).round() as usize;
            let (r0, r1) = (rank(a.min(b)), rank(a.max(b)));
            let samples = || data.iter().copied();
            let [k0, k1] = keys_of_ranks(samples, |n| [r0, r1].map(|r| r.min(n - 1))).unwrap();
            prop_assert_eq!(from_order_key(k0).to_bits(), sorted[r0].to_bits());
            prop_assert_eq!(from_order_key(k1).to_bits(), sorted[r1].to_bits());
            let [k] = keys_of_ranks(samples, |_| [r1]).unwrap();
            prop_assert_eq!(k, k1);
        }
    }

    #[test]
    fn no_samples_have_no_ranks() {
        assert_eq!(keys_of_ranks(std::iter::empty::<f32>, |_| [0]), None);
    }

    /// Keys order as `f32::total_cmp` orders the samples, and buckets as
    /// the keys do.
    #[test]
    fn keys_and_buckets_follow_the_order_of_the_samples() {
        let samples = [
            f32::NEG_INFINITY,
            -3.5,
            -1e-30,
            -0.0,
            0.0,
            1e-30,
            0.5,
            7.0,
            f32::INFINITY,
        ];
        for w in samples.windows(2) {
            let (k0, k1) = (order_key(w[0]), order_key(w[1]));
            assert!(k0 < k1, "{} {}", w[0], w[1]);
            assert!(bucket(k0) <= bucket(k1), "{} {}", w[0], w[1]);
            assert_eq!(from_order_key(k0).to_bits(), w[0].to_bits());
        }
    }
}
