//! Material-ratio (Abbott–Firestone) parameters: the Sk family (ISO 25178-2 Annex B /
//! ISO 13565-2), the volume parameters and Sxp.
//!
//! The curve is `h(q) = quantile(η, 1 − q)` (linear interpolation between order statistics,
//! numpy's default), sampled at 10 001 ratios for the 40 % window search and the equivalent
//! line. Areas and volumes are exact for the sample, `mean(max(η − c, 0))`, so plateaus of
//! tied heights (extruded simulated surfaces) cause no error.

/// Material-ratio parameters (heights µm relative to the mean, ratios %, volumes µm³/µm²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialRatio {
    /// Core height `Sk`.
    pub sk: f64,
    /// Reduced peak height `Spk`.
    pub spk: f64,
    /// Reduced valley depth `Svk`.
    pub svk: f64,
    /// Upper material ratio of the core `Smr1`, %.
    pub smr1: f64,
    /// Lower material ratio of the core `Smr2`, %.
    pub smr2: f64,
    /// Peak material volume at 10 %.
    pub vmp: f64,
    /// Core material volume between 10 % and 80 %.
    pub vmc: f64,
    /// Core void volume between 10 % and 80 %.
    pub vvc: f64,
    /// Valley void volume at 80 %.
    pub vvv: f64,
    /// Extreme peak height `Smc(2.5 %) − Smc(50 %)`.
    pub sxp: f64,
}

/// Sorted valid heights relative to their mean.
pub(crate) fn sorted_heights(z: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = z.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return v;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    for x in &mut v {
        *x -= mean;
    }
    v.sort_unstable_by(f64::total_cmp);
    v
}

/// numpy "linear" quantile of ascending `v` at `p` in [0, 1].
fn quantile(v: &[f64], p: f64) -> f64 {
    let pos = p.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    let f = pos - lo as f64;
    v[lo] + f * (v[hi] - v[lo])
}

/// Material ratio (fraction from the top) at which the quantile curve reaches height `c`.
fn ratio_at(v: &[f64], c: f64) -> f64 {
    let n = v.len();
    if c >= v[n - 1] {
        return 0.0;
    }
    if c <= v[0] {
        return 1.0;
    }
    // First index with v[k] > c; the curve crosses c between k-1 and k.
    let k = v.partition_point(|&x| x <= c);
    let (a, b) = (v[k - 1], v[k]);
    let f = if b > a { (c - a) / (b - a) } else { 0.0 };
    let p = ((k - 1) as f64 + f) / (n - 1) as f64;
    1.0 - p
}

fn mean_above(v: &[f64], c: f64) -> f64 {
    let k = v.partition_point(|&x| x <= c);
    v[k..].iter().map(|x| x - c).sum::<f64>() / v.len() as f64
}

fn mean_below(v: &[f64], c: f64) -> f64 {
    let k = v.partition_point(|&x| x < c);
    v[..k].iter().map(|x| c - x).sum::<f64>() / v.len() as f64
}

/// Material-ratio parameters of the finite values of `z`; `None` with fewer than 2 values.
pub fn material_ratio(z: &[f64]) -> Option<MaterialRatio> {
    let v = sorted_heights(z);
    material_ratio_sorted(&v)
}

/// As [`material_ratio`] on heights already sorted ascending (and mean-removed).
pub(crate) fn material_ratio_sorted(v: &[f64]) -> Option<MaterialRatio> {
    if v.len() < 2 {
        return None;
    }
    const NQ: usize = 10_001;
    let q: Vec<f64> = (0..NQ).map(|k| k as f64 / (NQ - 1) as f64).collect();
    let h: Vec<f64> = q.iter().map(|&qq| quantile(v, 1.0 - qq)).collect();
    let w = (0.4 * (NQ - 1) as f64).round() as usize;
    // Least steep 40 % secant (h decreases, so the largest difference), first on ties.
    let mut i0 = 0;
    let mut best = f64::NEG_INFINITY;
    for i in 0..NQ - w {
        let s = h[i + w] - h[i];
        if s > best {
            best = s;
            i0 = i;
        }
    }
    // Least-squares equivalent line h = α + β q over the window.
    let xs = &q[i0..=i0 + w];
    let ys = &h[i0..=i0 + w];
    let m = xs.len() as f64;
    let mx = xs.iter().sum::<f64>() / m;
    let my = ys.iter().sum::<f64>() / m;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (x, y) in xs.iter().zip(ys) {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
    }
    let beta = sxy / sxx;
    let alpha = my - beta * mx;
    let (y_up, y_lo) = (alpha, alpha + beta);
    let mr1 = ratio_at(v, y_up);
    let mr2 = ratio_at(v, y_lo);
    let a1 = mean_above(v, y_up);
    let a2 = mean_below(v, y_lo);
    let spk = if mr1 > 0.0 && a1 > 0.0 {
        2.0 * a1 / mr1
    } else {
        0.0
    };
    let svk = if mr2 < 1.0 && a2 > 0.0 {
        2.0 * a2 / (1.0 - mr2)
    } else {
        0.0
    };
    let c = |p: f64| quantile(v, 1.0 - p);
    let vm = |p: f64| mean_above(v, c(p));
    let vv = |p: f64| mean_below(v, c(p));
    Some(MaterialRatio {
        sk: y_up - y_lo,
        spk,
        svk,
        smr1: 100.0 * mr1,
        smr2: 100.0 * mr2,
        vmp: vm(0.10),
        vmc: vm(0.80) - vm(0.10),
        vvc: vv(0.10) - vv(0.80),
        vvv: vv(0.80),
        sxp: c(0.025) - c(0.50),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_matches_numpy_linear() {
        let v = [0.0, 1.0, 2.0, 4.0];
        assert_eq!(quantile(&v, 0.5), 1.5);
        assert_eq!(quantile(&v, 1.0), 4.0);
        assert!((ratio_at(&v, 3.0) - (1.0 - 2.5 / 3.0)).abs() < 1e-15);
    }

    #[test]
    fn volumes_exact_on_uniform_heights() {
        // Uniform heights on [-1, 1]: Vm(p) = p²·... exact for the sample; Vm(0.1) ≈ 0.01.
        let n = 100_001;
        let z: Vec<f64> = (0..n)
            .map(|k| -1.0 + 2.0 * k as f64 / (n - 1) as f64)
            .collect();
        let m = material_ratio(&z).unwrap();
        assert!((m.vmp - 0.01).abs() < 1e-4, "{m:?}");
        assert!((m.vvv - 0.04).abs() < 1e-4, "{m:?}");
        // A straight curve: the core is everything, Sk = 2.
        assert!((m.sk - 2.0).abs() < 1e-6, "{m:?}");
    }
}
