//! The integer counts the GPU accumulates for one hypothesis, and where each lives in its
//! slice of the counts buffer (shared with `shaders/verify/score.comp`):
//!
//! | words | content |
//! |---|---|
//! | 0..3 | N1+, N1−, N0 |
//! | 3..3+M | N_M: synthetic population of model surface m (index m − 1) |
//! | then K·M | t: pixels with sensed segment k and synthetic surface m, at (k − 1)·M + (m − 1) |
//! | then 2·M | A_M in area units (area.rs), as (low, high) u32 pairs |
//!
//! M is the model's surface count and K the sensed image's segment count. N1 (sensed valid,
//! synthetic not) is N_i − Σ t, so the GPU need only visit the pixels the model may cover.

/// Offsets and size of one hypothesis' counts, in u32 words.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CountsLayout {
    pub surfaces: u32,
    pub segments: u32,
}

/// Words of the scalars N1+, N1− and N0, then how many there are (where N_M starts). The
/// score pass gets these as specialization constants (src/verify/score_pass.rs).
pub const N1_PLUS_WORD: u32 = 0;
pub const N1_MINUS_WORD: u32 = 1;
pub const N0_WORD: u32 = 2;
pub const SCALARS: u32 = 3;

impl CountsLayout {
    pub fn populations(&self) -> usize {
        SCALARS as usize
    }

    pub fn overlaps(&self) -> usize {
        self.populations() + self.surfaces as usize
    }

    pub fn areas(&self) -> usize {
        self.overlaps() + self.segments as usize * self.surfaces as usize
    }

    pub fn words(&self) -> usize {
        self.areas() + 2 * self.surfaces as usize
    }

    /// The counts in `words`; `sensed_valid` is N_i, from which N1 follows.
    pub fn decode(&self, words: &[u32], sensed_valid: u64) -> Counts {
        let m = self.surfaces as usize;
        let overlaps = &words[self.overlaps()..self.areas()];
        let both_valid: u64 = overlaps.iter().map(|&t| u64::from(t)).sum();
        Counts {
            n1_plus: u64::from(words[N1_PLUS_WORD as usize]),
            n1_minus: u64::from(words[N1_MINUS_WORD as usize]),
            n0: u64::from(words[N0_WORD as usize]),
            n1: sensed_valid - both_valid,
            surface_population: words[self.populations()..self.overlaps()].iter().map(|&w| u64::from(w)).collect(),
            overlap: (0..self.segments as usize)
                .flat_map(|k| (0..m).map(move |j| (k, j)))
                .filter(|&(k, j)| overlaps[k * m + j] != 0)
                .map(|(k, j)| ((k as u32, j as u32 + 1), u64::from(overlaps[k * m + j])))
                .collect(),
            surface_area_units: words[self.areas()..self.words()]
                .chunks_exact(2)
                .map(|pair| u64::from(pair[0]) | (u64::from(pair[1]) << 32))
                .collect(),
        }
    }
}

/// What one hypothesis' synthetic image counts against the sensed image.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize)]
pub struct Counts {
    /// Pixels valid in both within the tolerance.
    pub n1_plus: u64,
    /// Pixels valid in both where the prediction is closer than sensed by more than τ.
    pub n1_minus: u64,
    /// Synthetic valid, sensed invalid.
    pub n0: u64,
    /// Sensed valid, synthetic invalid.
    pub n1: u64,
    /// N_M per model surface (index m − 1).
    pub surface_population: Vec<u64>,
    /// t per (dense segment index, model surface), only where non-zero, in index order.
    pub overlap: Vec<((u32, u32), u64)>,
    /// A_M per model surface in area units (index m − 1).
    pub surface_area_units: Vec<u64>,
}

impl Counts {
    /// Bytes its lists hold on the heap.
    pub(crate) fn heap_bytes(&self) -> u64 {
        (self.surface_population.capacity() * size_of::<u64>()
            + self.overlap.capacity() * size_of::<((u32, u32), u64)>()
            + self.surface_area_units.capacity() * size_of::<u64>()) as u64
    }

    /// N_s: synthetic valid pixels.
    pub fn synthetic_valid(&self) -> u64 {
        self.surface_population.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every word lands where the table above says, an area's high word included (a surface
    /// of more than 65,536 pixel areas: 2^32 units).
    #[test]
    fn decode_reads_every_word_where_the_layout_puts_it() {
        let layout = CountsLayout { surfaces: 2, segments: 2 };
        let words = [7, 1, 2, 4, 3, 0, 5, 2, 0, 9, 0, 3, 6];
        assert_eq!(layout.words(), words.len());
        let counts = layout.decode(&words, 20);
        assert_eq!(
            counts,
            Counts {
                n1_plus: 7,
                n1_minus: 1,
                n0: 2,
                n1: 20 - 7,
                surface_population: vec![4, 3],
                overlap: vec![((0, 2), 5), ((1, 1), 2)],
                surface_area_units: vec![9, 6 << 32 | 3],
            }
        );
    }
}
