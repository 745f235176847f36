//! Insertion order: merging bit-identical duplicates, and the BRIO order
//! (a seeded shuffle in rounds of doubling size, each sorted along a Morton
//! curve; Amenta, Choi & Rote 2003) that keeps the location walk short.

use super::predicates::P3;
use crate::sampling::SampleRng;

/// Sorts indices by exact position and keeps the lowest index of each group.
pub(super) fn merge_duplicates(pts: &[P3]) -> (Vec<u32>, Vec<(u32, u32)>) {
    let mut idx: Vec<u32> = (0..pts.len() as u32).collect();
    let key = |i: u32| {
        let p = pts[i as usize];
        (p[0].to_bits(), p[1].to_bits(), p[2].to_bits(), i)
    };
    idx.sort_unstable_by_key(|&i| key(i));
    let mut unique = Vec::with_capacity(pts.len());
    let mut merged = Vec::new();
    let mut g = 0;
    while g < idx.len() {
        let kept = idx[g];
        let mut h = g + 1;
        while h < idx.len() && pts[idx[h] as usize] == pts[kept as usize] {
            merged.push((idx[h], kept));
            h += 1;
        }
        unique.push(kept);
        g = h;
    }
    merged.sort_unstable();
    (unique, merged)
}

/// Spreads the low 21 bits of `v` so that two zero bits follow each bit.
pub(super) fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f00000000ffff;
    x = (x | (x << 16)) & 0x1f0000ff0000ff;
    x = (x | (x << 8)) & 0x100f00f00f00f00f;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3;
    x = (x | (x << 2)) & 0x1249249249249249;
    x
}

/// BRIO insertion order: seeded shuffle, rounds of doubling size, each sorted
/// by Morton code (21 bits per axis over the bounding box).
pub(super) fn brio_order(pts: &[P3], mut order: Vec<u32>) -> Vec<u32> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in &order {
        for k in 0..3 {
            lo[k] = lo[k].min(pts[i as usize][k]);
            hi[k] = hi[k].max(pts[i as usize][k]);
        }
    }
    let scale: [f64; 3] = std::array::from_fn(|k| {
        let ext = hi[k] - lo[k];
        if ext > 0.0 {
            ((1u64 << 21) - 1) as f64 / ext
        } else {
            0.0
        }
    });
    let morton = |i: u32| {
        let p = pts[i as usize];
        let q = |k: usize| ((p[k] - lo[k]) * scale[k]) as u64;
        spread3(q(0)) | (spread3(q(1)) << 1) | (spread3(q(2)) << 2)
    };
    let mut rng = SampleRng::from_state(0x005E_ED0F_B810);
    for i in (1..order.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    // Round boundaries from the end: the last round holds half the points.
    const FIRST_ROUND: usize = 64;
    let mut bounds = vec![order.len()];
    let mut end = order.len();
    while end > FIRST_ROUND {
        end /= 2;
        bounds.push(end);
    }
    bounds.push(0);
    bounds.reverse();
    let mut sorted = Vec::with_capacity(order.len());
    for w in bounds.windows(2) {
        let round: Vec<(u64, u32)> = order[w[0]..w[1]].iter().map(|&i| (morton(i), i)).collect();
        sorted.extend(bucket_sort_by_key(round, 63).into_iter().map(|(_, i)| i));
    }
    sorted
}

/// Sorts `(key, value)` pairs by key, then value, for keys below `2^bits`:
/// one counting-sort pass on the top 12 key bits, then a comparison sort of
/// each (small, cache-resident) bucket. Same order as `sort_unstable` on the
/// pairs, about twice as fast on the builder's ~7 tets per point.
pub(super) fn bucket_sort_by_key(a: Vec<(u64, u32)>, bits: u32) -> Vec<(u64, u32)> {
    const TOP: u32 = 12;
    let shift = bits.saturating_sub(TOP);
    let bucket = |k: u64| (k >> shift) as usize & ((1 << TOP) - 1);
    let mut start = vec![0usize; (1 << TOP) + 1];
    for &(k, _) in &a {
        start[bucket(k) + 1] += 1;
    }
    for i in 0..1 << TOP {
        start[i + 1] += start[i];
    }
    let mut next = start.clone();
    let mut b = vec![(0u64, 0u32); a.len()];
    for &e in &a {
        let d = bucket(e.0);
        b[next[d]] = e;
        next[d] += 1;
    }
    for w in start.windows(2) {
        b[w[0]..w[1]].sort_unstable();
    }
    b
}
