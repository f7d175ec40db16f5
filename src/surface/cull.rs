//! Culling: keeping only the samples whose tool can reach a region, so that time and memory
//! follow the grid rather than the path. Runs are split where samples are dropped, so the
//! engine never joins two samples across a gap; θ and t keep their values.

use crate::math::Point3;
use crate::resample::Sample;

/// Samples accumulated from a stream, keeping those that [`Subset::push`] is told to keep.
#[derive(Debug, Default)]
pub struct Subset {
    /// The kept samples, runs renumbered (a new run after every gap).
    pub samples: Vec<Sample>,
    last_source_run: Option<usize>,
    dropped_since: bool,
    next_run: usize,
    /// Samples seen.
    pub seen: usize,
}

impl Subset {
    /// Count `count` samples of the stream that were not built (they cannot reach the grid).
    pub fn skip(&mut self, count: usize) {
        self.seen += count;
        self.dropped_since = true;
    }

    /// Take one sample of the stream (in order); `keep` says whether it can reach the grid.
    pub fn push(&mut self, s: &Sample, keep: bool) {
        self.seen += 1;
        if !keep {
            self.dropped_since = true;
            return;
        }
        let new_run = self.last_source_run != Some(s.run) || self.dropped_since;
        if new_run && !self.samples.is_empty() {
            self.next_run += 1;
        }
        self.last_source_run = Some(s.run);
        self.dropped_since = false;
        let mut k = s.clone();
        k.run = self.next_run;
        self.samples.push(k);
    }
}

/// An axis-aligned box in the WCS, possibly unbounded along some axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Lower corner (−∞ where unbounded).
    pub lo: Point3,
    /// Upper corner (+∞ where unbounded).
    pub hi: Point3,
}

impl Reach {
    /// A box around `centre` of half-size `half` along every axis.
    pub fn around(centre: &Point3, half: f64) -> Reach {
        Reach {
            lo: centre - crate::math::Vec3::repeat(half),
            hi: centre + crate::math::Vec3::repeat(half),
        }
    }

    /// Whether `p` lies within `margin` of the box.
    pub fn near(&self, p: &Point3, margin: f64) -> bool {
        (0..3).all(|k| p[k] >= self.lo[k] - margin && p[k] <= self.hi[k] + margin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn sample(run: usize, x: f64) -> Sample {
        Sample {
            run,
            s_mm: x,
            t_s: 0.0,
            theta_rad: x,
            position: Point3::new(x, 0.0, 0.0),
            axis: Vec3::z(),
            contact: None,
            normal: None,
            feed_dir: Vec3::x(),
            feed_mm_min: 1.0,
        }
    }

    #[test]
    fn gaps_and_run_changes_start_new_runs() {
        let mut s = Subset::default();
        for (run, x, keep) in [
            (0, 0.0, true),
            (0, 1.0, true),
            (0, 2.0, false),
            (0, 3.0, true),
            (1, 4.0, true),
            (1, 5.0, true),
        ] {
            s.push(&sample(run, x), keep);
        }
        let runs: Vec<usize> = s.samples.iter().map(|k| k.run).collect();
        assert_eq!(runs, vec![0, 0, 1, 2, 2]);
        assert_eq!(s.samples[2].theta_rad, 3.0);
        assert_eq!(s.seen, 6);
    }
}
