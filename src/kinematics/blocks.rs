//! Preprocessing and constraints in the path parameter (kinematics.md §4–§5): per-block
//! speed, acceleration and jerk limits (Eq 2 in arc-length form), junction ceilings
//! (Eq 3) and the junction spacing rule (§5.3).

use super::chain::Joints;
use super::machine::Limits;
use rayon::prelude::*;

/// Floor on the block length for pure re-orientation blocks, mm (§4).
///
/// kinematics.md suggests 1e-6 mm. Every limit scales with L, so the value only sets the
/// scale of s inside such a block; at 1e-6 mm the per-cycle jerk terms of a rotation block
/// fall to a few ULP of s (about 1e-15 mm at s ≈ 5 mm) and the feasibility tests of the
/// interpolator lose their precision. 1e-3 mm keeps them well resolved and changes the
/// block time by less than a microsecond.
pub const EPS_L: f64 = 1e-3;

/// The constraint that limits a block or a posture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// The programmed feed F.
    Feed,
    /// The velocity limit of joint `i`.
    Velocity(usize),
    /// The block-cycle rule (a block lasts at least `min_block_cycles` cycles).
    BlockCycle,
    /// A junction ceiling (Eq 3 or the spacing rule).
    Junction,
    /// Speeding up or slowing down, bounded by the acceleration or jerk of joint `i`.
    Ramp(usize),
    /// The stop must fit within the look-ahead window.
    Lookahead,
    /// Rest at the path ends or at an exact stop.
    Stop,
}

impl Limit {
    /// Short label with the machine's joint names: `F`, `vmax:C`, `block_cycle`,
    /// `junction`, `ramp:X`, `lookahead`, `stop`.
    pub fn label(&self, names: &[&str; 5]) -> String {
        match self {
            Limit::Feed => "F".into(),
            Limit::Velocity(i) => format!("vmax:{}", names[*i]),
            Limit::BlockCycle => "block_cycle".into(),
            Limit::Junction => "junction".into(),
            Limit::Ramp(i) => format!("ramp:{}", names[*i]),
            Limit::Lookahead => "lookahead".into(),
            Limit::Stop => "stop".into(),
        }
    }
}

/// Settings of the constraints, from the machine file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Interpolation cycle T, s.
    pub cycle_time: f64,
    /// A block lasts at least this many cycles (0 disables).
    pub min_block_cycles: f64,
    /// Look-ahead window in blocks (0 = unlimited).
    pub lookahead_blocks: usize,
    /// Apply §5.3.
    pub junction_spacing_rule: bool,
}

/// The path cut into blocks, with every limit in the path parameter s (mm of CL path).
#[derive(Debug, Clone, Default)]
pub struct Blocks {
    /// L_k, mm (floored at [`EPS_L`]).
    pub len: Vec<f64>,
    /// S_p, the path parameter at posture p (one more entry than blocks).
    pub start: Vec<f64>,
    /// g_k = Δq_k / L_k (mm/mm and rad/mm).
    pub g: Vec<Joints>,
    /// v̄_k, mm/s.
    pub vbar: Vec<f64>,
    /// What sets v̄_k.
    pub vbar_by: Vec<Limit>,
    /// ā_k, mm/s².
    pub abar: Vec<f64>,
    /// j̄_k, mm/s³.
    pub jbar: Vec<f64>,
    /// Joint that sets j̄_k.
    pub jbar_by: Vec<usize>,
    /// Axis-only velocity limit min_i Vmax_i/|g_i| (for the self-check), mm/s.
    pub vaxis: Vec<f64>,
    /// Ceiling c_p at each posture, mm/s.
    pub ceil: Vec<f64>,
    /// True where c_p comes from Eq 3 / §5.3 (lower than both adjacent v̄).
    pub ceil_junction: Vec<bool>,
}

impl Blocks {
    /// Number of blocks.
    pub fn n(&self) -> usize {
        self.len.len()
    }

    /// Build the blocks from joints per posture, CL positions, the programmed feed per block
    /// (mm/s, `f64::INFINITY` = none) and exact-stop flags per posture.
    pub fn build(
        joints: &[Joints],
        positions: &[[f64; 3]],
        feed: &[f64],
        exact_stop: &[bool],
        limits: &[Limits; 5],
        settings: &Settings,
    ) -> Blocks {
        let np = joints.len();
        let nb = np.saturating_sub(1);
        let mut b = Blocks {
            len: vec![0.0; nb],
            start: vec![0.0; np],
            g: vec![[0.0; 5]; nb],
            vbar: vec![0.0; nb],
            vbar_by: vec![Limit::Feed; nb],
            abar: vec![0.0; nb],
            jbar: vec![0.0; nb],
            jbar_by: vec![0; nb],
            vaxis: vec![0.0; nb],
            ceil: vec![0.0; np],
            ceil_junction: vec![false; np],
        };
        let mut still = vec![false; nb];
        // Per block, independent: in parallel, straight into the columns.
        (
            &mut b.len,
            &mut b.g,
            &mut b.vbar,
            &mut b.vbar_by,
            &mut b.abar,
            &mut b.jbar,
            &mut b.jbar_by,
            &mut b.vaxis,
            &mut still,
        )
            .into_par_iter()
            .enumerate()
            .for_each(
                |(k, (len, g, vbar, vbar_by, abar, jbar, jbar_by, vaxis, still))| {
                    let (p, q) = (positions[k], positions[k + 1]);
                    let dl =
                        ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2))
                            .sqrt();
                    let l = dl.max(EPS_L);
                    for i in 0..5 {
                        g[i] = (joints[k + 1][i] - joints[k][i]) / l;
                    }
                    let (mut vax, mut vax_by) = (f64::INFINITY, 0);
                    let mut a = f64::INFINITY;
                    let (mut j, mut j_by) = (f64::INFINITY, 0);
                    for i in 0..5 {
                        let gi = g[i].abs();
                        if gi > 0.0 {
                            let lim = &limits[i];
                            if lim.vmax / gi < vax {
                                vax = lim.vmax / gi;
                                vax_by = i;
                            }
                            a = a.min(lim.amax / gi);
                            if lim.jmax / gi < j {
                                j = lim.jmax / gi;
                                j_by = i;
                            }
                        }
                    }
                    *still = dl < EPS_L && g.iter().all(|x| x.abs() < 1e-12);
                    let f = feed.get(k).copied().unwrap_or(f64::INFINITY);
                    // The NC drops blocks without motion, so the block-cycle rule skips them.
                    let cyc = if settings.min_block_cycles > 0.0 && !*still {
                        l / (settings.min_block_cycles * settings.cycle_time)
                    } else {
                        f64::INFINITY
                    };
                    let (mut v, mut by) = (f, Limit::Feed);
                    if vax < v {
                        v = vax;
                        by = Limit::Velocity(vax_by);
                    }
                    if cyc < v {
                        v = cyc;
                        by = Limit::BlockCycle;
                    }
                    if !v.is_finite() {
                        // No axis moves, no feed and no block-cycle rule: the block is free.
                        v = 1e9;
                    }
                    if !a.is_finite() {
                        a = 1e9;
                    }
                    if !j.is_finite() {
                        j = 1e12;
                    }
                    (*len, *vbar, *vbar_by, *abar, *jbar, *jbar_by, *vaxis) =
                        (l, v, by, a, j, j_by, vax);
                },
            );
        let mut s = 0.0;
        for (k, l) in b.len.iter().enumerate() {
            s += l;
            b.start[k + 1] = s;
        }
        // Direction used for the junction on each side of a block: a block with no motion
        // at all (a repeated posture) carries its predecessor's, so it is transparent.
        let mut from = vec![0u32; nb];
        for k in 1..nb {
            from[k] = if still[k] { from[k - 1] } else { k as u32 };
        }
        let g_junction = |k: usize| &b.g[from[k] as usize];
        let ceilings: Vec<(f64, bool)> = (1..nb)
            .into_par_iter()
            .map(|p| {
                let mut c = b.vbar[p - 1].min(b.vbar[p]);
                if c >= 1e9 {
                    // Between two free blocks.
                    c = 1e9;
                }
                let lmin = b.len[p - 1].min(b.len[p]);
                let mut junction = false;
                let (gjp, gjm) = (g_junction(p), g_junction(p - 1));
                for ((&gp, &gm), lim) in gjp.iter().zip(gjm).zip(limits) {
                    let dg = (gp - gm).abs();
                    if dg <= 1e-12 * (gp.abs() + gm.abs()) || dg == 0.0 {
                        continue;
                    }
                    let eq3 = (8.0 * lim.amax * lim.tol).sqrt() / dg;
                    if eq3 < c {
                        c = eq3;
                        junction = true;
                    }
                    if settings.junction_spacing_rule {
                        let sp = (lim.amax * lmin / dg).sqrt();
                        if sp < c {
                            c = sp;
                            junction = true;
                        }
                    }
                }
                if exact_stop.get(p).copied().unwrap_or(false) {
                    c = 0.0;
                    junction = false;
                }
                (c, junction)
            })
            .collect();
        for (p, (c, junction)) in (1..nb).zip(ceilings) {
            b.ceil[p] = c;
            b.ceil_junction[p] = junction;
        }
        b
    }

    /// Time at the programmed feed, Σ L/F, s; blocks without a feed count at their axis
    /// velocity limit.
    pub fn programmed_time(&self, feed: &[f64]) -> f64 {
        (0..self.n())
            .map(|k| {
                let f = feed.get(k).copied().unwrap_or(f64::INFINITY);
                let v = if f.is_finite() { f } else { self.vaxis[k] };
                if v.is_finite() && v > 0.0 {
                    self.len[k] / v
                } else {
                    0.0
                }
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::machine::{Machine, TABLE_I_AC_TOML};
    use approx::assert_relative_eq;

    fn setup(joints: &[Joints], feed_mm_min: f64) -> Blocks {
        let m = Machine::from_toml_str(TABLE_I_AC_TOML).unwrap();
        let settings = Settings {
            cycle_time: m.cycle_time,
            min_block_cycles: m.min_block_cycles,
            lookahead_blocks: 0,
            junction_spacing_rule: true,
        };
        let pos: Vec<[f64; 3]> = joints.iter().map(|q| [q[0], q[1], q[2]]).collect();
        let feed = vec![feed_mm_min / 60.0; joints.len() - 1];
        Blocks::build(
            joints,
            &pos,
            &feed,
            &vec![false; joints.len()],
            &m.joint_limits(),
            &settings,
        )
    }

    #[test]
    fn r5_inverse_time_limits() {
        // model.md R5: ΔX = 1 mm, ΔA = 0.5°, Vf = 5 m/min: v̂ ≤ 83.333 s⁻¹ (F binds),
        // â ≤ 2160 s⁻², ĵ ≤ 40000 s⁻³. With L = 1 mm, v̂ = v̄/L.
        let b = setup(
            &[[0.0; 5], [1.0, 0.0, 0.0, 0.5f64.to_radians(), 0.0]],
            5000.0,
        );
        assert_relative_eq!(b.vbar[0] / b.len[0], 83.333333, max_relative = 1e-6);
        assert_eq!(b.vbar_by[0], Limit::Feed);
        assert_relative_eq!(b.abar[0] / b.len[0], 2160.0, max_relative = 1e-6);
        assert_relative_eq!(b.jbar[0] / b.len[0], 40000.0, max_relative = 1e-6);
    }

    #[test]
    fn r5_block_cycle_and_junctions() {
        // Block of 0.1 mm: feed ≤ 0.1/0.003 = 2000 mm/min.
        let b = setup(&[[0.0; 5], [0.1, 0.0, 0.0, 0.0, 0.0]], 5000.0);
        assert_relative_eq!(b.vbar[0] * 60.0, 2000.0, max_relative = 1e-9);
        assert_eq!(b.vbar_by[0], Limit::BlockCycle);
        // 90° XY corner: 1200 mm/min.
        let b = setup(
            &[
                [0.0; 5],
                [50.0, 0.0, 0.0, 0.0, 0.0],
                [50.0, 50.0, 0.0, 0.0, 0.0],
            ],
            5000.0,
        );
        assert_relative_eq!(b.ceil[1] * 60.0, 1200.0, max_relative = 1e-6);
        assert!(b.ceil_junction[1]);
        assert_eq!((b.ceil[0], b.ceil[2]), (0.0, 0.0));
        // 10° corner: 6910.5 mm/min.
        let d = 10f64.to_radians();
        let b = setup(
            &[
                [0.0; 5],
                [50.0, 0.0, 0.0, 0.0, 0.0],
                [50.0 + 50.0 * d.cos(), 50.0 * d.sin(), 0.0, 0.0, 0.0],
            ],
            10_000.0,
        );
        assert_relative_eq!(b.ceil[1] * 60.0, 6910.5, max_relative = 1e-5);
    }

    #[test]
    fn spacing_rule_tends_to_centripetal_limit() {
        // K5 idea: circle R = 5 mm in 5° chords at 50 m/min, no block-cycle rule. Eq 3 alone
        // lets 20/|Δg| ≈ 229 mm/s through; the spacing rule gives about sqrt(A R) = 158 mm/s.
        let r = 5.0;
        let joints: Vec<Joints> = (0..=72)
            .map(|k| {
                let t = (5.0 * k as f64).to_radians();
                [r * t.cos(), r * t.sin(), 0.0, 0.0, 0.0]
            })
            .collect();
        let m = Machine::from_toml_str(TABLE_I_AC_TOML).unwrap();
        let pos: Vec<[f64; 3]> = joints.iter().map(|q| [q[0], q[1], q[2]]).collect();
        let build = |rule: bool| {
            Blocks::build(
                &joints,
                &pos,
                &[50_000.0 / 60.0; 72],
                &[false; 73],
                &m.joint_limits(),
                &Settings {
                    cycle_time: 0.003,
                    min_block_cycles: 0.0,
                    lookahead_blocks: 0,
                    junction_spacing_rule: rule,
                },
            )
        };
        let on = build(true);
        let off = build(false);
        // At 180° the chord turn is all in x.
        let dg = 2.0 * 2.5f64.to_radians().sin();
        let chord = 2.0 * r * 2.5f64.to_radians().sin();
        assert_relative_eq!(off.ceil[36], 20.0 / dg, max_relative = 1e-3);
        assert_relative_eq!(
            on.ceil[36],
            (5000.0 * chord / dg).sqrt(),
            max_relative = 1e-3
        );
        let centripetal = (5000.0f64 * r).sqrt();
        assert!((on.ceil[36] / centripetal - 1.0).abs() < 0.01);
        assert!(on.ceil.iter().zip(&off.ceil).all(|(a, b)| a <= b));
    }
}
