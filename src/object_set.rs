//! A fixed-size set of object ids as a bitset: drawn sets, visible sets.

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ObjectSet {
    words: Vec<u32>,
}

impl ObjectSet {
    pub fn new(objects: usize) -> Self {
        ObjectSet {
            words: vec![0; objects.div_ceil(32)],
        }
    }

    /// The set whose bits are `words` (bit i of word w is object 32·w + i),
    /// as the GPU writes it.
    pub fn from_words(words: Vec<u32>) -> Self {
        ObjectSet { words }
    }

    pub fn clear(&mut self) {
        self.words.fill(0);
    }

    pub fn insert(&mut self, object: u32) {
        self.words[object as usize / 32] |= 1 << (object % 32);
    }

    pub fn contains(&self, object: u32) -> bool {
        self.words
            .get(object as usize / 32)
            .is_some_and(|w| w & (1 << (object % 32)) != 0)
    }

    pub fn len(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.words.iter().all(|&w| w == 0)
    }

    /// Number of members of `self` that `other` lacks.
    pub fn count_missing_from(&self, other: &ObjectSet) -> usize {
        self.words
            .iter()
            .enumerate()
            .map(|(i, &w)| (w & !other.words.get(i).copied().unwrap_or(0)).count_ones() as usize)
            .sum()
    }

    /// Members in increasing order.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        self.words.iter().enumerate().flat_map(|(i, &w)| {
            (0..32)
                .filter(move |b| w & (1 << b) != 0)
                .map(move |b| i as u32 * 32 + b)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_operations_agree_with_a_vec() {
        let mut a = ObjectSet::new(100);
        let mut b = ObjectSet::new(100);
        for i in [0, 5, 31, 32, 63, 99] {
            a.insert(i);
        }
        for i in [5, 32, 64] {
            b.insert(i);
        }
        assert_eq!(a.iter().collect::<Vec<_>>(), vec![0, 5, 31, 32, 63, 99]);
        assert_eq!(a.len(), 6);
        assert!(a.contains(99) && !a.contains(98) && !a.contains(1000));
        assert_eq!(a.count_missing_from(&b), 4);
        assert_eq!(b.count_missing_from(&a), 1);
        a.clear();
        assert!(a.is_empty());
    }
}
