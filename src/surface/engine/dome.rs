//! The dome model's strips: the angles and levels of each sample's revolved body that can
//! come below the band ([`Setup::dome_strips`]), and, for one tile, the part of a strip
//! worth meshing ([`Setup::dome_narrow`]).

use super::{DOME_CHUNK, Setup, Strip};
use crate::math::Vec3;
use crate::surface::envelope::{DomeSweep, dome_low};
use crate::surface::raster::Tile;
use std::f64::consts::{PI, TAU};

/// Angles per run whose box [`Setup::dome_narrow`] tests against the tile.
const DOME_RUN: i64 = 4;

impl Setup<'_> {
    /// The dome strips of sample `k`: per tooth, runs of [`DOME_CHUNK`] mesh angles of the
    /// levels of its revolved body that can come below `thr`, each with its node-space box;
    /// runs whose box lies beyond the grid are left out (no tile would take them).
    pub(super) fn dome_strips(&self, k: usize, thr: f64) -> (Vec<Strip>, Vec<[f64; 4]>) {
        let mut strips = Vec::new();
        let mut boxes = Vec::new();
        let base = self.pose(k, 0.0, false);
        let Some((_, hi)) = self.candidates(&base, thr) else {
            return (strips, boxes);
        };
        let reach = (self.profile.reach[hi] + self.profile.runout_bound) / self.d;
        if base.b.x + reach < 0.0
            || base.b.y + reach < 0.0
            || base.b.x - reach > (self.nx - 1) as f64
            || base.b.y - reach > (self.ny - 1) as f64
        {
            return (strips, boxes);
        }
        let (a, b) = (base.m[(2, 0)], base.m[(2, 1)]);
        let amp = (a * a + b * b).sqrt();
        let m22 = base.m[(2, 2)];
        // W(φ) = c + r (a sin φ + b cos φ) is lowest at φ* (where it equals c − r amp).
        let phi_star = -0.5 * PI - b.atan2(a);
        for j in 0..self.cutter_teeth {
            if self.dome_repeat[j] {
                continue;
            }
            let body = &self.profile.body[j];
            let mut lo = usize::MAX;
            let mut hi = 0;
            let mut half = 0.0f64;
            let mut r_max = 0.0f64;
            for (i, e) in body.iter().enumerate() {
                let c = base.b.z + e.z * m22;
                let r = e.y;
                if c - r * amp > thr {
                    continue;
                }
                // The end face's levels between the first below `thr` and its rim share
                // `c`, and `r` grows along them: their half-widths lie between the two
                // ends', so only the ends need one.
                let inner = lo < i && i < self.profile.flat;
                lo = lo.min(i);
                hi = i;
                r_max = r_max.max(r);
                if inner {
                    continue;
                }
                let h = if r * amp < 1e-12 {
                    PI
                } else {
                    let s0 = (thr - c) / (r * amp);
                    (-s0).clamp(-1.0, 1.0).acos()
                };
                half = half.max(h);
            }
            if lo == usize::MAX {
                continue;
            }
            let lo = lo.saturating_sub(1);
            let hi = (hi + 1).min(body.len() - 1);
            for e in &body[lo..=hi] {
                r_max = r_max.max(e.y);
            }
            // The points the mesh uses (its boxes are theirs).
            let kept: Vec<Vec3> = self.profile.dome_levels(lo, hi).map(|i| body[i]).collect();
            let dphi = (8.0 * self.opts.chord_tol_mm / r_max.max(1e-6))
                .sqrt()
                .clamp(1e-4, 1f64.to_radians());
            let n = ((TAU / dphi).ceil() as i64).max(8);
            let n = n + (n & 1); // even: φ = 0 and π are mesh angles
            let step = TAU / n as f64;
            let (m0, m1) = if half >= PI - 1e-12 {
                (0, n)
            } else {
                let m0 = ((phi_star - half) / step).floor() as i64 - 1;
                let m1 = ((phi_star + half) / step).ceil() as i64 + 1;
                if m1 - m0 >= n { (0, n) } else { (m0, m1) }
            };
            let sweep = DomeSweep::new(&base.m, &base.b, &kept);
            let (gx, gy) = ((self.nx - 1) as f64 + 1e-9, (self.ny - 1) as f64 + 1e-9);
            let mut c0 = m0;
            while c0 < m1 {
                let c1 = (c0 + DOME_CHUNK).min(m1);
                let (t0, t1) = (c0 as f64 * step, c1 as f64 * step);
                let bb = sweep.dome_box(t0, t1);
                // Beyond the grid: no tile would take it.
                if bb[2] < -1e-9 || bb[3] < -1e-9 || bb[0] > gx || bb[1] > gy {
                    c0 = c1;
                    continue;
                }
                strips.push(Strip {
                    k: k as u32,
                    a: c0,
                    b: c1,
                    n: n as u32,
                    tooth: j as u16,
                    lo: lo as u16,
                    hi: hi as u16,
                });
                boxes.push(bb);
                c0 = c1;
            }
        }
        (strips, boxes)
    }

    /// Narrow dome strip `s` to the angles and levels that can lower a node of `tile` below
    /// `cull` (`kept`: space for the body points); `false` when none can.
    pub(super) fn dome_narrow(
        &self,
        s: &mut Strip,
        tile: &Tile,
        cull: f64,
        kept: &mut Vec<Vec3>,
    ) -> bool {
        // Only the angles and levels with a corner below the tile's cull.
        let base = self.pose(s.k as usize, 0.0, false);
        let body = &self.profile.body[s.tooth as usize][s.lo as usize..=s.hi as usize];
        let step = TAU / f64::from(s.n);
        let face = self.profile.flat.saturating_sub(s.lo as usize);
        let low = dome_low(&base.m, base.b.z, body, (s.a, s.b), step, cull, face);
        let Some(((a, b), (l0, l1))) = low else {
            return false;
        };
        (s.a, s.b, s.hi, s.lo) = (a, b, s.lo + l1 as u16, s.lo + l0 as u16);
        // Only the angles whose points can reach the tile's nodes, by the boxes of
        // runs of a few angles (the triangles of the others lie beyond the tile).
        if s.b - s.a > DOME_RUN {
            let (lo, hi) = (s.lo as usize, s.hi as usize);
            let body = &self.profile.body[s.tooth as usize];
            kept.clear();
            kept.extend(self.profile.dome_levels(lo, hi).map(|i| body[i]));
            let sweep = DomeSweep::new(&base.m, &base.b, kept);
            let (x0, y0) = (tile.i0 as f64 - 1e-6, tile.j0 as f64 - 1e-6);
            let x1 = (tile.i0 + tile.w - 1) as f64 + 1e-6;
            let y1 = (tile.j0 + tile.h - 1) as f64 + 1e-6;
            let mut hit: Option<(i64, i64)> = None;
            let mut m = s.a;
            while m < s.b {
                let e = (m + DOME_RUN).min(s.b);
                let bb = sweep.dome_box(m as f64 * step, e as f64 * step);
                if !(bb[2] < x0 || bb[3] < y0 || bb[0] > x1 || bb[1] > y1) {
                    hit = Some(hit.map_or((m, e), |(h0, _)| (h0, e)));
                }
                m = e;
            }
            let Some((a, b)) = hit else {
                return false;
            };
            (s.a, s.b) = (a, b);
        }
        true
    }
}
