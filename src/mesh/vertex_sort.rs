//! Sorting keys that lead with a vertex index: a counting sort by that vertex, then each
//! vertex's few keys sorted. The result is the order `sort_unstable` gives on the whole slice
//! (equal keys are identical), without its O(n log n) comparisons over all keys.

/// Sorts `keys` ascending. `vertex(k)` is the key's leading vertex index (below `n`); the keys'
/// order must sort a smaller leading vertex first.
pub(crate) fn sort_by_vertex<K: Ord + Copy + Default>(
    keys: &mut Vec<K>,
    n: usize,
    vertex: impl Fn(&K) -> u32,
) {
    let mut start = vec![0usize; n + 1];
    for k in keys.iter() {
        start[vertex(k) as usize + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut out = vec![K::default(); keys.len()];
    for &k in keys.iter() {
        let v = vertex(&k) as usize;
        out[fill[v]] = k;
        fill[v] += 1;
    }
    for v in 0..n {
        out[start[v]..start[v + 1]].sort_unstable();
    }
    *keys = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equals_sort_unstable() {
        let mut x = 12345u64;
        let mut next = |n: u64| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((x >> 33) % n) as u32
        };
        for len in [0usize, 1, 2, 17, 500] {
            let mut keys: Vec<(u32, u32, u32)> =
                (0..len).map(|_| (next(20), next(20), next(5))).collect();
            let mut expect = keys.clone();
            expect.sort_unstable();
            sort_by_vertex(&mut keys, 20, |k| k.0);
            assert_eq!(keys, expect);
            let mut tri: Vec<([u32; 3], usize)> = (0..len)
                .map(|f| {
                    let mut k = [next(9), next(9), next(9)];
                    k.sort_unstable();
                    (k, f % 7)
                })
                .collect();
            let mut expect = tri.clone();
            expect.sort_unstable();
            sort_by_vertex(&mut tri, 9, |k| k.0[0]);
            assert_eq!(tri, expect);
        }
    }
}
