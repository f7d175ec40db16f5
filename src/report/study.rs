//! Designed experiments (001 §4 and appendix): full-factorial designs over tool orientation
//! and cutting parameters, and the factor effects of 001 Eqs 7-8.
//!
//! A design lists factors with their levels; the runs are the full factorial in the order of
//! the 001 appendix: the first factor varies slowest, the last fastest. Each run gets one
//! value per response (a surface parameter such as `Sq`). The effect of factor i at level j
//! is `EF_ij = M_ij − M` (Eq 7), where `M_ij` is the mean response over the runs with factor
//! i at level j and `M` the mean over all runs; Eq 8 divides the first-level effect by the
//! mean, `EF_i1 = (M_i1 − M)/M`, so that parameters of different units compare.

/// One factor and its levels.
#[derive(Debug, Clone, PartialEq)]
pub struct Factor {
    /// Name, with its unit (`tilt_deg`, `feed_mm_min`).
    pub name: String,
    /// Levels in order.
    pub levels: Vec<f64>,
}

/// The runs of a full-factorial design: for each run, the level index of each factor, in
/// appendix order (first factor slowest, last fastest).
pub fn full_factorial(factors: &[Factor]) -> Vec<Vec<usize>> {
    let n_runs: usize = factors.iter().map(|f| f.levels.len()).product();
    if factors.is_empty() || n_runs == 0 {
        return Vec::new();
    }
    let mut runs = Vec::with_capacity(n_runs);
    for run in 0..n_runs {
        let mut rest = run;
        let mut idx = vec![0; factors.len()];
        for (i, f) in factors.iter().enumerate().rev() {
            idx[i] = rest % f.levels.len();
            rest /= f.levels.len();
        }
        runs.push(idx);
    }
    runs
}

/// Factor effects of one response.
#[derive(Debug, Clone, PartialEq)]
pub struct Effects {
    /// Mean over all runs, M.
    pub mean: f64,
    /// `effects[i][j] = M_ij − M` (Eq 7).
    pub effects: Vec<Vec<f64>>,
    /// `relative_first[i] = (M_i1 − M)/M` (Eq 8); NaN when M = 0.
    pub relative_first: Vec<f64>,
}

/// Eqs 7-8 for one response: `runs` as from [`full_factorial`], `response[run]`.
/// Runs whose response is not finite are left out of every mean.
pub fn factor_effects(factors: &[Factor], runs: &[Vec<usize>], response: &[f64]) -> Effects {
    let finite: Vec<(usize, f64)> = response
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .collect();
    let mean = if finite.is_empty() {
        f64::NAN
    } else {
        finite.iter().map(|(_, v)| v).sum::<f64>() / finite.len() as f64
    };
    let mut effects = Vec::with_capacity(factors.len());
    for (i, f) in factors.iter().enumerate() {
        let mut row = Vec::with_capacity(f.levels.len());
        for j in 0..f.levels.len() {
            let (sum, n) = finite
                .iter()
                .filter(|(r, _)| runs[*r][i] == j)
                .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
            row.push(if n == 0 {
                f64::NAN
            } else {
                sum / n as f64 - mean
            });
        }
        effects.push(row);
    }
    let relative_first = effects
        .iter()
        .map(|row| {
            if mean != 0.0 {
                row.first().copied().unwrap_or(f64::NAN) / mean
            } else {
                f64::NAN
            }
        })
        .collect();
    Effects {
        mean,
        effects,
        relative_first,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn doe16() -> Vec<Factor> {
        let f = |name: &str, levels: &[f64]| Factor {
            name: name.into(),
            levels: levels.to_vec(),
        };
        vec![
            f("yaw_deg", &[0.0, 20.0]),
            f("tilt_deg", &[1.0, 10.0]),
            f("scallop_um", &[5.0, 10.0]),
            f("feed_mm_min", &[2000.0, 4000.0]),
        ]
    }

    #[test]
    fn full_factorial_follows_the_001_appendix_order() {
        let factors = doe16();
        let runs = full_factorial(&factors);
        assert_eq!(runs.len(), 16);
        // Appendix rows 1, 2, 5, 9 and 16.
        let value = |r: usize| -> Vec<f64> {
            runs[r]
                .iter()
                .enumerate()
                .map(|(i, &j)| factors[i].levels[j])
                .collect()
        };
        assert_eq!(value(0), vec![0.0, 1.0, 5.0, 2000.0]);
        assert_eq!(value(1), vec![0.0, 1.0, 5.0, 4000.0]);
        assert_eq!(value(4), vec![0.0, 10.0, 5.0, 2000.0]);
        assert_eq!(value(8), vec![20.0, 1.0, 5.0, 2000.0]);
        assert_eq!(value(15), vec![20.0, 10.0, 10.0, 4000.0]);
    }

    #[test]
    fn effects_of_an_additive_response_are_its_coefficients() {
        // y = 10 + 3·[yaw high] − 2·[feed high]: a balanced design recovers ±1.5 and ∓1.
        let factors = doe16();
        let runs = full_factorial(&factors);
        let y: Vec<f64> = runs
            .iter()
            .map(|r| 10.0 + 3.0 * r[0] as f64 - 2.0 * r[3] as f64)
            .collect();
        let e = factor_effects(&factors, &runs, &y);
        assert_relative_eq!(e.mean, 10.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[0][0], -1.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[0][1], 1.5, epsilon = 1e-12);
        assert_relative_eq!(e.effects[1][0], 0.0, epsilon = 1e-12);
        assert_relative_eq!(e.effects[3][0], 1.0, epsilon = 1e-12);
        assert_relative_eq!(e.relative_first[0], -1.5 / 10.5, epsilon = 1e-12);
        // Effects over the levels of a factor sum to zero in a balanced design.
        for row in &e.effects {
            assert_relative_eq!(row.iter().sum::<f64>(), 0.0, epsilon = 1e-12);
        }
    }
}
