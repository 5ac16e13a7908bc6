//! Joining equal keys (corner positions, vertex attributes, grid cells)
//! through one flat open-addressing table of indices.
//!
//! Welding and vertex joining look up a key once per triangle corner, so
//! the table is the hot loop of smoothing and tangent frames. It is sized
//! by the number of distinct keys (grown on demand) rather than by the
//! number of lookups, so that it stays small enough for the caches: a
//! million-triangle model has about six corners per distinct position.
//! Each slot holds an index into the caller's own array of keys and 32
//! bits of the key's hash, so that a probe reads the caller's key only
//! when the hashes agree (almost always a true match), and growing the
//! table needs no key at all.

/// An open-addressing (linear probing) table of `u32` indices, keyed by
/// the caller: it stores indices and hash tags, the caller keeps the keys
/// and says whether the key behind an index equals the one sought.
pub(crate) struct IndexTable {
    slots: Vec<Slot>,
    /// `32 - log2(slots.len())`: a slot number is the top bits of a tag.
    shift: u32,
    len: usize,
}

#[derive(Clone, Copy)]
struct Slot {
    tag: u32,
    index: u32,
}

const EMPTY: Slot = Slot {
    tag: 0,
    index: u32::MAX,
};

impl IndexTable {
    /// A table for about `expected` distinct keys (it grows beyond).
    pub(crate) fn with_capacity(expected: usize) -> Self {
        // At most half full, so that probe sequences stay short.
        let slots = (expected.saturating_mul(2)).next_power_of_two().max(16);
        IndexTable {
            slots: vec![EMPTY; slots],
            shift: 32 - slots.trailing_zeros(),
            len: 0,
        }
    }

    /// Reads the first slot of each hash, so that the lookups that follow
    /// find them in the cache: the reads are independent, so the processor
    /// waits for their cache misses together rather than one by one (a
    /// lookup's branch on what it found stops it from running ahead).
    #[inline]
    pub(crate) fn touch(&self, hashes: &[u64]) {
        let mut any = 0;
        for &hash in hashes {
            any ^= self.slots[(tag_of(hash) >> self.shift) as usize].index;
        }
        std::hint::black_box(any);
    }

    /// The index stored under a key equal to the sought one (`same(index)`
    /// says whether the key behind a stored index is equal), or `new`
    /// after storing it there.
    #[inline]
    pub(crate) fn get_or_insert(&mut self, hash: u64, new: u32, same: impl Fn(u32) -> bool) -> u32 {
        debug_assert!(new != u32::MAX);
        let tag = tag_of(hash);
        let mask = self.slots.len() - 1;
        let mut slot = (tag >> self.shift) as usize;
        loop {
            let held = self.slots[slot];
            if held.index == u32::MAX {
                self.slots[slot] = Slot { tag, index: new };
                self.len += 1;
                if self.len * 2 > self.slots.len() {
                    self.grow();
                }
                return new;
            }
            if held.tag == tag && same(held.index) {
                return held.index;
            }
            slot = (slot + 1) & mask;
        }
    }

    /// Doubles the slots, placing each entry by its tag alone.
    fn grow(&mut self) {
        let slots = self.slots.len() * 2;
        let old = std::mem::replace(&mut self.slots, vec![EMPTY; slots]);
        self.shift = 32 - slots.trailing_zeros();
        let mask = slots - 1;
        for held in old.into_iter().filter(|s| s.index != u32::MAX) {
            let mut slot = (held.tag >> self.shift) as usize;
            while self.slots[slot].index != u32::MAX {
                slot = (slot + 1) & mask;
            }
            self.slots[slot] = held;
        }
    }
}

/// The tag kept in a slot: the top 32 bits of the hash, which a
/// multiplicative hash mixes best. A slot number is the tag's top bits
/// (tables beyond 2^32 slots would need more, but indices are `u32`, and a
/// table is at most twice as large as its entries).
#[inline]
fn tag_of(hash: u64) -> u32 {
    (hash >> 32) as u32
}

/// A hash of 32-bit words: multiply-xorshift over pairs of words, then a
/// final mix so that the top bits depend on every input bit. Not
/// DoS-resistant (the keys come from a file the user chose to load), but a
/// few multiplications per key.
#[inline]
pub(crate) fn hash_words<const N: usize>(words: [u32; N]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15_u64;
    let mut i = 0;
    while i < N {
        let pair = if i + 1 < N {
            u64::from(words[i]) | (u64::from(words[i + 1]) << 32)
        } else {
            u64::from(words[i])
        };
        h = (h ^ pair).wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 29;
        i += 2;
    }
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every key is found again after the table has grown many times, and
    /// distinct keys get distinct indices.
    #[test]
    fn keys_survive_growth() {
        let keys: Vec<[u32; 3]> = (0..100_000u32).map(|i| [i % 977, i / 977, 7]).collect();
        let mut table = IndexTable::with_capacity(1);
        for (i, k) in keys.iter().enumerate() {
            let got = table.get_or_insert(hash_words(*k), i as u32, |j| keys[j as usize] == *k);
            assert_eq!(got, i as u32);
        }
        for (i, k) in keys.iter().enumerate() {
            let again =
                table.get_or_insert(hash_words(*k), u32::MAX - 1, |j| keys[j as usize] == *k);
            assert_eq!(again, i as u32);
        }
        assert_eq!(table.get_or_insert(hash_words([5, 5, 5]), 7, |_| false), 7);
    }

    /// Keys whose hashes collide (a constant hash) are still told apart by
    /// the caller's comparison.
    #[test]
    fn colliding_hashes_are_told_apart() {
        let mut table = IndexTable::with_capacity(4);
        for i in 0..100u32 {
            assert_eq!(table.get_or_insert(42, i, |j| j == i), i);
        }
        for i in 0..100u32 {
            assert_eq!(table.get_or_insert(42, 1000, |j| j == i), i);
        }
    }
}
