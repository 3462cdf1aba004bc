//! Least-significant-digit radix sort by a `u64` key: stable, linear in the items, for the
//! large sorts of the stitching stage (triangle grid entries, band sample candidates) where a
//! comparison sort dominated the profile.

/// Sorts `items` by `key` ascending, stable (items with equal keys keep their order): 11 bits a
/// pass over the bits the largest key uses, a pass whose digit is the same in every item
/// skipped. Short inputs go to the standard library's stable sort.
pub(crate) fn sort_by_key<T: Copy>(items: &mut Vec<T>, key: impl Fn(&T) -> u64) {
    const BITS: u32 = 11;
    const RADIX: usize = 1 << BITS;
    if items.len() < 256 {
        items.sort_by_key(&key);
        return;
    }
    let max = items.iter().map(&key).max().unwrap_or(0);
    let used = u64::BITS - max.leading_zeros();
    let mut other: Vec<T> = Vec::with_capacity(items.len());
    let mut count = vec![0usize; RADIX];
    let mut shift = 0;
    while shift < used {
        count.iter_mut().for_each(|c| *c = 0);
        let digit = |t: &T| ((key(t) >> shift) as usize) & (RADIX - 1);
        for t in items.iter() {
            count[digit(t)] += 1;
        }
        if count[digit(&items[0])] != items.len() {
            let mut sum = 0;
            for c in count.iter_mut() {
                let n = *c;
                *c = sum;
                sum += n;
            }
            other.clear();
            other.resize(items.len(), items[0]);
            for t in items.iter() {
                let d = digit(t);
                other[count[d]] = *t;
                count[d] += 1;
            }
            std::mem::swap(items, &mut other);
        }
        shift += BITS;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ordered like the standard library's stable sort by the same key: short and long inputs,
    /// keys spread over few and many bits, repeats (their payload order kept), and digits
    /// constant in every key (skipped passes).
    #[test]
    fn radix_sort_equals_stable_sort() {
        let mut rng = crate::phantom::rng::Rng::new(11);
        for len in [0usize, 1, 255, 256, 1000, 70_000] {
            for mask in [0u64, 7, 0xffff, 0x7ff << 22 | 0xff, u64::MAX] {
                let mut items: Vec<(u64, u32)> = (0..len as u32)
                    .map(|i| (rng.next_u64() & mask, i))
                    .collect();
                let mut expect = items.clone();
                expect.sort_by_key(|t| t.0);
                sort_by_key(&mut items, |t| t.0);
                assert_eq!(items, expect, "len {len} mask {mask:x}");
            }
        }
    }
}
