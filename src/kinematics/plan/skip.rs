//! The look-ahead skip tables: minima over chunks of blocks and postures, and the
//! next-lower chains of ā and j̄.

use crate::kinematics::blocks::Blocks;

/// Blocks (and postures) per chunk of the look-ahead skip tables.
pub(super) const CHUNK: usize = 16;

/// Minima of ā (blocks) and the ceilings (postures) over chunks of [`CHUNK`] entries, so
/// that the look-ahead scans skip whole chunks that cannot bind. The minima are exact, so
/// the scans give the same answers as visiting every entry.
///
/// Also, per block, the next block with a strictly lower ā (and j̄): the minimum over a run
/// of blocks from k is the last block of that chain inside the run, so `limits_over` hops
/// over the records instead of visiting every block.
pub(super) struct Chunks {
    pub(super) abar: Vec<f64>,
    pub(super) ceil: Vec<f64>,
    pub(super) next_lower_a: Vec<u32>,
    pub(super) next_lower_j: Vec<u32>,
}

/// For every index, the next index with a strictly lower value (`x.len()` if none).
fn next_lower(x: &[f64]) -> Vec<u32> {
    let mut out = vec![x.len() as u32; x.len()];
    let mut stack: Vec<usize> = Vec::new();
    for (i, &xi) in x.iter().enumerate() {
        while let Some(&top) = stack.last() {
            if xi < x[top] {
                out[top] = i as u32;
                stack.pop();
            } else {
                break;
            }
        }
        stack.push(i);
    }
    out
}

impl Chunks {
    pub(super) fn new(b: &Blocks) -> Chunks {
        let mins = |x: &[f64]| -> Vec<f64> {
            x.chunks(CHUNK)
                .map(|c| c.iter().copied().fold(f64::INFINITY, f64::min))
                .collect()
        };
        Chunks {
            abar: mins(&b.abar),
            ceil: mins(&b.ceil),
            next_lower_a: next_lower(&b.abar),
            next_lower_j: next_lower(&b.jbar),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_lower_chains_give_range_minima() {
        let x = [5.0, 3.0, 4.0, 3.0, 1.0, 2.0, 2.0, 0.5, 7.0];
        let next = next_lower(&x);
        assert_eq!(next, vec![1, 4, 3, 4, 7, 7, 7, 9, 9]);
        for k in 0..x.len() {
            for end in k..x.len() {
                let mut m = k;
                while (next[m] as usize) <= end {
                    m = next[m] as usize;
                }
                let want = x[k..=end].iter().copied().fold(f64::INFINITY, f64::min);
                assert_eq!(x[m], want, "{k}..={end}");
            }
        }
    }
}
