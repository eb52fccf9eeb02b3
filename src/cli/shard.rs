//! `verify --shard i/N`: the i-th (from 0) of N contiguous, near-equal ranges of a file's
//! hypotheses, so that N runs (a Slurm job array, a Kubernetes Indexed Job, one per GPU) split
//! a file, and their outputs, concatenated in shard order, are the unsharded output byte for
//! byte (each hypothesis scores the same alone or in any batch).

use std::ops::Range;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let bad = || format!("{text:?} is not i/N with 0 ≤ i < N (the i-th of N shards, from 0)");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) =
            (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        match index < count {
            true => Ok(Self { index, count }),
            false => Err(bad()),
        }
    }
}

impl Shard {
    /// This shard's hypotheses of `total`: from ⌊i·total/N⌋ up to ⌊(i+1)·total/N⌋.
    pub fn range(&self, total: usize) -> Range<usize> {
        let at = |k: usize| ((k as u128 * total as u128) / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 10 hypotheses in 4 shards: 2, 3, 2, 3, one after another, covering all; more shards
    /// than hypotheses leave some empty.
    #[test]
    fn shards_are_contiguous_near_equal_and_cover_every_hypothesis() {
        let ranges: Vec<_> = (0..4).map(|index| Shard { index, count: 4 }.range(10)).collect();
        assert_eq!(ranges, [0..2, 2..5, 5..7, 7..10]);
        let few: Vec<usize> = (0..5).map(|index| Shard { index, count: 5 }.range(3).len()).collect();
        assert_eq!(few, [0, 1, 0, 1, 1]);
    }

    #[test]
    fn a_shard_is_read_as_i_of_n() {
        assert_eq!("2/8".parse::<Shard>(), Ok(Shard { index: 2, count: 8 }));
        for bad in ["8/8", "3", "-1/4", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().unwrap_err().contains("not i/N"), "{bad}");
        }
    }
}
