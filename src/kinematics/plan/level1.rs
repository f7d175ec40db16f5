//! Level 1 (kinematics.md §6.1): the exact acceleration-limited look-ahead.

use super::Timing;
use crate::kinematics::blocks::Blocks;

/// Level 1 (§6.1): acceleration-limited look-ahead, forward and backward pass, then a
/// trapezoid per block. Exact and O(N); no jerk.
pub fn plan_acc_only(b: &Blocks) -> Timing {
    let n = b.n();
    let np = n + 1;
    let mut vin = vec![0.0; np];
    let mut vout = vec![0.0; n];
    for k in 0..n {
        let reach = (vin[k] * vin[k] + 2.0 * b.abar[k] * b.len[k]).sqrt();
        vout[k] = b.ceil[k + 1].min(b.vbar[k]).min(reach);
        vin[k + 1] = vout[k];
    }
    vin[n] = 0.0;
    for k in (0..n).rev() {
        vout[k] = vout[k].min(vin[k + 1]);
        let reach = (vout[k] * vout[k] + 2.0 * b.abar[k] * b.len[k]).sqrt();
        vin[k] = vin[k].min(reach);
    }
    let mut t = vec![0.0; np];
    let mut peak = vec![0.0; n];
    for k in 0..n {
        let (a, l) = (b.abar[k], b.len[k]);
        let (v0, v1) = (vin[k], vout[k]);
        let vp = b.vbar[k]
            .min(((v0 * v0 + v1 * v1 + 2.0 * a * l) / 2.0).sqrt())
            .max(v0.max(v1));
        let d_up = (vp * vp - v0 * v0) / (2.0 * a);
        let d_dn = (vp * vp - v1 * v1) / (2.0 * a);
        let cruise = (l - d_up - d_dn).max(0.0);
        let dt = (vp - v0) / a + (vp - v1) / a + if vp > 0.0 { cruise / vp } else { 0.0 };
        t[k + 1] = t[k] + dt;
        peak[k] = vp;
    }
    Timing {
        total: t[n],
        t,
        v: vin,
        block_peak: peak,
        max_axis_ratio: 0.0,
        max_ceiling_ratio: 0.0,
        cycles: 0,
        fallbacks: 0,
        searches: 0,
        stop_recoveries: 0,
    }
}
