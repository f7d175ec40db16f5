//! Process effects beyond geometry: the minimum uncut chip thickness (ploughing) with
//! elastic recovery, applied pass by pass in cutting order, and a seeded Gaussian random
//! texture. All are off by default; see `docs/process-effects.md` for the equations.
//!
//! **Ploughing.** A tooth pass at a node brings its own lowest height `w` there. With `z` the
//! height the node has when the pass arrives (`+∞` before the first), the uncut chip along
//! the normal is `h = z − w`. The pass removes the material (`z ← w`) only when `h ≥ h_min`;
//! a thinner layer is ploughed: it passes under the edge and springs back by the fraction
//! `recovery` of its depth (`z ← w + recovery·(z − w)`; 1 = whole, Brammertz's and
//! Vogler–DeVor–Kapoor's assumption). A later pass whose chip reaches `h_min` removes it.
//!
//! **Texture.** A stationary Gaussian field of standard deviation Sq and autocorrelation
//! `exp(−r²/ℓ²)` (ℓ = the correlation length, where it falls to 1/e), as a sum of
//! [`TEXTURE_MODES`] random-phase cosines whose wave vectors are drawn from its spectrum.
//! It is a function of the node's position alone, so it does not depend on tiles or threads.

use crate::math::rng::Rng;
use std::f64::consts::TAU;

/// Cosine modes of the texture field.
pub const TEXTURE_MODES: usize = 256;

/// A seeded Gaussian random texture added to the surface.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Texture {
    /// Standard deviation of the heights, mm.
    pub sq_mm: f64,
    /// Correlation length ℓ (autocorrelation exp(−r²/ℓ²)), mm.
    pub corr_mm: f64,
    /// Seed of the field.
    pub seed: u64,
}

/// The process effects of a simulation (all off by default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Process {
    /// Minimum uncut chip thickness h_min, mm (0 = every pass cuts: the geometric surface).
    pub min_chip_mm: f64,
    /// Fraction of a ploughed layer's depth that springs back (0..1; 1 = all of it).
    pub recovery: f64,
    /// Random texture added to the heights.
    pub texture: Option<Texture>,
}

impl Default for Process {
    fn default() -> Self {
        Process {
            min_chip_mm: 0.0,
            recovery: 1.0,
            texture: None,
        }
    }
}

impl Process {
    /// Whether passes must be applied in cutting order with the chip rule.
    pub fn ploughs(&self) -> bool {
        self.min_chip_mm > 0.0
    }

    /// Whether every effect is off (the geometric surface).
    pub fn is_off(&self) -> bool {
        !self.ploughs() && self.texture.is_none_or(|t| t.sq_mm == 0.0)
    }

    /// Check the values; the message names the key of `process.toml`.
    pub fn check(&self) -> Result<(), ProcessError> {
        if !(self.min_chip_mm.is_finite() && self.min_chip_mm >= 0.0) {
            return Err(ProcessError::MinChip(self.min_chip_mm * 1e3));
        }
        if !(0.0..=1.0).contains(&self.recovery) {
            return Err(ProcessError::Recovery(self.recovery));
        }
        if let Some(t) = self.texture {
            if !(t.sq_mm.is_finite() && t.sq_mm >= 0.0) {
                return Err(ProcessError::TextureSq(t.sq_mm * 1e3));
            }
            if !(t.corr_mm.is_finite() && t.corr_mm > 0.0) {
                return Err(ProcessError::TextureCorr(t.corr_mm * 1e3));
            }
        }
        Ok(())
    }
}

/// A process value out of its range; the message names the key of `process.toml`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProcessError {
    /// A negative or non-finite minimum chip, µm.
    #[error("min_chip_um must be ≥ 0, got {0}")]
    MinChip(f64),
    /// A recovery outside 0..1.
    #[error("recovery must lie in 0..1, got {0}")]
    Recovery(f64),
    /// A negative or non-finite texture Sq, µm.
    #[error("texture_sq_um must be ≥ 0, got {0}")]
    TextureSq(f64),
    /// A non-positive texture correlation length, µm.
    #[error("texture_corr_um must be positive, got {0}")]
    TextureCorr(f64),
}

/// One pass applied to a node at height `z` (`+∞` = stock): the pass's lowest height `w`.
#[inline]
pub fn apply_pass(z: f64, w: f64, min_chip: f64, recovery: f64) -> f64 {
    if w >= z {
        z
    } else if z - w >= min_chip {
        w
    } else {
        w + recovery * (z - w)
    }
}

/// The texture as a function of position: `value(x, y)` in mm for x, y in mm.
#[derive(Debug, Clone)]
pub struct TextureField {
    amp: f64,
    modes: Vec<[f64; 3]>,
}

impl TextureField {
    /// The field of `t`: wave vectors k ~ N(0, 2/ℓ²) per component (the spectrum of
    /// exp(−r²/ℓ²)), phases uniform, amplitude Sq·√(2/M).
    pub fn new(t: &Texture) -> TextureField {
        let mut rng = Rng::new(t.seed);
        let s = 2f64.sqrt() / t.corr_mm;
        let modes = (0..TEXTURE_MODES)
            .map(|_| {
                let kx = s * rng.normal();
                let ky = s * rng.normal();
                [kx, ky, TAU * rng.uniform()]
            })
            .collect();
        TextureField {
            amp: t.sq_mm * (2.0 / TEXTURE_MODES as f64).sqrt(),
            modes,
        }
    }

    /// Height of the texture at (x, y), mm.
    pub fn value(&self, x: f64, y: f64) -> f64 {
        if self.amp == 0.0 {
            return 0.0;
        }
        self.amp * self.mode_sum(x, y)
    }

    /// The sum of the modes' cosines at (x, y): the field at (x, y) is `amp` times it.
    fn mode_sum(&self, x: f64, y: f64) -> f64 {
        self.modes
            .iter()
            .map(|m| (m[0] * x + m[1] * y + m[2]).cos())
            .sum::<f64>()
    }
}

/// Rows of mode sums remembered per thread (see [`texture_row`]).
const ROW_MEMO: usize = 8;

/// A row's key: seed, ℓ and dx as bits, and the number of steps.
type RowKey = (u64, u64, u64, usize);

thread_local! {
    static ROWS: std::cell::RefCell<Vec<(RowKey, std::rc::Rc<[f64]>)>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The texture `t` along y = 0 at x = i·dx for i = 0..=n (mm): exactly
/// `TextureField::new(t).value(i as f64 * dx, 0.0)` for each i.
///
/// The field's amplitude is Sq times a factor of the mode count, and its modes depend only
/// on the seed and ℓ; a Monte Carlo study or a calibration evaluates the same profile with
/// many Sq, and the 256 cosines per point were 64 % of such a run's time (`perf`, the Monte
/// Carlo property test). So the rows of mode sums are remembered per thread (the last
/// [`ROW_MEMO`] keys) and only scaled here: the same bits as evaluating the field.
pub fn texture_row(t: &Texture, dx: f64, n: usize) -> Vec<f64> {
    let field = TextureField::new(t);
    if field.amp == 0.0 {
        return vec![0.0; n + 1];
    }
    let key = (t.seed, t.corr_mm.to_bits(), dx.to_bits(), n);
    let sums = ROWS.with(|rows| {
        let mut rows = rows.borrow_mut();
        if let Some(i) = rows.iter().position(|(k, _)| *k == key) {
            let hit = rows.remove(i);
            rows.push(hit.clone());
            return hit.1;
        }
        let sums: std::rc::Rc<[f64]> = (0..=n)
            .map(|i| field.mode_sum(i as f64 * dx, 0.0))
            .collect();
        if rows.len() == ROW_MEMO {
            rows.remove(0);
        }
        rows.push((key, sums.clone()));
        sums
    });
    sums.iter().map(|s| field.amp * s).collect()
}

/// The 1-D surface left by passes in time order: `passes[i](x)` is pass i's height at x
/// (mm; `+∞` where it does not reach), applied with the chip rule at every x of `xs`.
pub fn profile_1d(xs: &[f64], passes: &[&dyn Fn(f64) -> f64], p: &Process) -> Vec<f64> {
    xs.iter()
        .map(|&x| {
            passes.iter().fold(f64::INFINITY, |z, f| {
                apply_pass(z, f(x), p.min_chip_mm, p.recovery)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brammertz (1961), as quoted by e.g. Weule, Hüntrup & Tritschler (CIRP Annals 50/1,
    /// 2001, Eq 1): Rt = f²/(8 rε) + (h_min/2)(1 + rε·h_min/f²).
    fn brammertz(r: f64, s: f64, h: f64) -> f64 {
        s * s / (8.0 * r) + 0.5 * h * (1.0 + r * h / (s * s))
    }

    #[test]
    fn one_d_ploughing_matches_brammertz_from_its_minimum_up() {
        let r: f64 = 5.0;
        for h in [0.001f64, 0.0025] {
            let s_min = (2.0 * r * h).sqrt();
            for f in [1.0, 1.2, 1.5, 2.0, 3.0] {
                let s = s_min * f;
                let n = 40;
                let arcs: Vec<Box<dyn Fn(f64) -> f64>> = (0..n)
                    .map(|i| {
                        let c = i as f64 * s;
                        Box::new(move |x: f64| {
                            let d = x - c;
                            if d.abs() < r {
                                r - (r * r - d * d).sqrt()
                            } else {
                                f64::INFINITY
                            }
                        }) as Box<dyn Fn(f64) -> f64>
                    })
                    .collect();
                let refs: Vec<&dyn Fn(f64) -> f64> = arcs.iter().map(|b| b.as_ref()).collect();
                let p = Process {
                    min_chip_mm: h,
                    ..Process::default()
                };
                let x0 = 30.0 * s;
                let xs: Vec<f64> = (0..=4000).map(|i| x0 + s * i as f64 / 2000.0).collect();
                let z = profile_1d(&xs, &refs, &p);
                let rt = z.iter().copied().fold(f64::MIN, f64::max)
                    - z.iter().copied().fold(f64::MAX, f64::min);
                let want = brammertz(r, s, h);
                assert!(
                    (rt / want - 1.0).abs() < 0.02,
                    "h {h} s {s}: {rt} against {want}"
                );
            }
        }
    }

    #[test]
    fn texture_has_its_sq_and_depends_only_on_position() {
        let t = Texture {
            sq_mm: 0.001,
            corr_mm: 0.01,
            seed: 3,
        };
        let f = TextureField::new(&t);
        let n = 400;
        let mut sum2 = 0.0;
        for j in 0..n {
            for i in 0..n {
                let v = f.value(i as f64 * 0.005, j as f64 * 0.005);
                sum2 += v * v;
            }
        }
        let sq = (sum2 / (n * n) as f64).sqrt();
        assert!((sq / 0.001 - 1.0).abs() < 0.1, "{sq}");
        assert_eq!(f.value(0.3, 0.7), TextureField::new(&t).value(0.3, 0.7));
        // A row is the field's values, bit for bit, remembered or not, for any Sq.
        for sq in [0.001, 0.0004, 0.001] {
            let t = Texture { sq_mm: sq, ..t };
            let f = TextureField::new(&t);
            let row = texture_row(&t, 0.0007, 300);
            assert_eq!(row.len(), 301);
            for (i, v) in row.iter().enumerate() {
                assert_eq!(
                    v.to_bits(),
                    f.value(i as f64 * 0.0007, 0.0).to_bits(),
                    "{i}"
                );
            }
        }
        let zero = Texture { sq_mm: 0.0, ..t };
        assert_eq!(texture_row(&zero, 0.0007, 3), [0.0; 4]);
        assert!(apply_pass(f64::INFINITY, 1.0, 0.5, 1.0) == 1.0);
        assert!(apply_pass(1.2, 1.0, 0.5, 1.0) == 1.2);
        assert!(apply_pass(1.2, 1.0, 0.5, 0.5) == 1.1);
    }
}
