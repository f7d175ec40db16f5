//! Triangle rasterisation into a tile of the z-buffer (minimum height at each node).
//!
//! Vertices are given in node-index space: X = column, Y = row (both fractional), W = the
//! height along the grid normal, mm. A node is inside a triangle when it lies on or within
//! its edges (with a 1e-9 node tolerance), so triangles that share an edge leave no gap:
//! the swept surface is covered whatever the grid.

use crate::math::{ceil_fast, floor_fast};

/// A tile of the z-buffer: columns `[i0, i0 + w)`, rows `[j0, j0 + h)`, row-major.
#[derive(Debug, Clone)]
pub(crate) struct Tile {
    pub i0: usize,
    pub j0: usize,
    pub w: usize,
    pub h: usize,
    /// Lowest height reached at each node, mm (`+∞` = not reached).
    pub z: Vec<f64>,
    /// Per block of `BLOCK × BLOCK` nodes: an upper bound of `z` there (exact when it was
    /// last recomputed; `z` only decreases), and whether a triangle has been drawn over the
    /// block since.
    bmax: Vec<f64>,
    dirty: Vec<bool>,
    /// Per row and block column: the largest height of the row's piece of the block (its
    /// up to `BLOCK` nodes), always exact (recomputed whenever a node of it is lowered).
    smax: Vec<f64>,
    /// Blocks per row.
    bw: usize,
    /// An upper bound of `z` over the whole tile: its highest node when [`Tile::top`] last
    /// looked (`z` only decreases since), `+∞` before.
    top_bound: f64,
    /// The blocks the triangle being drawn has written (marked dirty when it is done).
    written: Vec<usize>,
}

/// Side of the blocks of [`Tile`]'s occlusion bounds, nodes.
const BLOCK: usize = 8;
/// Nodes of a triangle's box from which stale block bounds are recomputed for it.
const MIN_REFRESH_NODES: usize = 16;

impl Tile {
    pub fn new(i0: usize, j0: usize, w: usize, h: usize) -> Tile {
        let bw = w.div_ceil(BLOCK);
        let nb = bw * h.div_ceil(BLOCK);
        Tile {
            i0,
            j0,
            w,
            h,
            z: vec![f64::INFINITY; w * h],
            bmax: vec![f64::INFINITY; nb],
            dirty: vec![false; nb],
            smax: vec![f64::INFINITY; bw * h],
            bw,
            top_bound: f64::INFINITY,
            written: Vec::new(),
        }
    }

    /// The highest height of the tile once every node has been reached (`None` before):
    /// no triangle lying above it can lower a node. Recomputes the stale block bounds.
    pub fn top(&mut self) -> Option<f64> {
        let mut top = f64::NEG_INFINITY;
        for b in 0..self.bmax.len() {
            if self.dirty[b] {
                self.bmax[b] = block_max(&self.smax, self.bw, b % self.bw, b / self.bw);
                self.dirty[b] = false;
            }
            top = top.max(self.bmax[b]);
        }
        self.top_bound = top;
        top.is_finite().then_some(top)
    }

    /// Rasterise the triangle `a`, `b`, `c` ([X, Y, W]) unless its lowest vertex is above
    /// `cull_w`; each covered node keeps the minimum of its height and the triangle's.
    /// A triangle that lies above every node it could reach (by the block bounds) is
    /// skipped: it would lower none of them.
    #[inline]
    pub fn triangle(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3], cull_w: f64) {
        let rect = (self.i0, self.j0, self.w, self.h);
        // What `cover` would return at once on, decided before the bounds below are.
        if misses(rect, &[a, b, c], cull_w) {
            return;
        }
        let (bmax, dirty, bw, smax) = (&mut self.bmax, &mut self.dirty, self.bw, &self.smax);
        let w = self.w;
        let mut occluded = |cols: (usize, usize), rows: (usize, usize), low: f64, refresh: bool| {
            let (bx0, bx1) = (cols.0 / BLOCK, cols.1 / BLOCK);
            let (by0, by1) = (rows.0 / BLOCK, rows.1 / BLOCK);
            // Bounds as they stand first; then refresh the stale ones one at a time.
            for by in by0..=by1 {
                for bx in bx0..=bx1 {
                    let b = by * bw + bx;
                    if bmax[b] > low && (!dirty[b] || !refresh) {
                        return false;
                    }
                }
            }
            for by in by0..=by1 {
                for bx in bx0..=bx1 {
                    let b = by * bw + bx;
                    if bmax[b] > low {
                        bmax[b] = block_max(smax, bw, bx, by);
                        dirty[b] = false;
                        if bmax[b] > low {
                            return false;
                        }
                    }
                }
            }
            true
        };
        let low = lower_bound(&a, &b, &c);
        // Above the whole tile: nothing else need be looked at.
        if low.is_some_and(|low| self.top_bound <= low) {
            return;
        }
        // No node within reach: `spans` would find none either (its rows and columns lie
        // within these).
        let Some((cols, rows)) = reach(rect, &a, &b, &c, cull_w) else {
            return;
        };
        if let Some(low) = low {
            // Columns one node wider than the box: the edge crossings are rounded.
            let lc = (
                cols.0.max(self.i0 + 1) - 1 - self.i0,
                (cols.1 + 1).min(self.i0 + w - 1) - self.i0,
            );
            let lr = (rows.0 - self.j0, rows.1 - self.j0);
            // Refreshing bounds pays only for triangles that span several nodes.
            let big = (lc.1 - lc.0 + 1) * (lr.1 - lr.0 + 1) >= MIN_REFRESH_NODES;
            if occluded(lc, lr, low, big) {
                return;
            }
        }
        self.lower(a, b, c, cull_w);
    }

    /// Lower the nodes the triangle covers to its height, row by row in pieces of one
    /// block: a piece whose lowest height (at one of its ends: the height is monotonic
    /// along a row, rounding included) is not below its block's bound lowers no node and
    /// is skipped. The bounds of the blocks written before this triangle are refreshed
    /// when it first meets them; those it writes are marked afterwards.
    fn lower(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3], cull_w: f64) {
        let rect = (self.i0, self.j0, self.w, self.h);
        let (i0, j0, w) = (self.i0, self.j0, self.w);
        let (dirty, bw, z, smax) = (&mut self.dirty, self.bw, &mut self.z, &mut self.smax);
        let written = &mut self.written;
        written.clear();
        spans(rect, a, b, c, cull_w, |row, c0, c1, base, gx| {
            let r = row - j0;
            let off = r * w;
            let by = r / BLOCK;
            let mut p0 = c0 - i0;
            let last = c1 - i0;
            while p0 <= last {
                let bx = p0 / BLOCK;
                let seg = r * bw + bx;
                let p1 = ((bx + 1) * BLOCK - 1).min(last);
                let (w0, w1) = (base + gx * (i0 + p0) as f64, base + gx * (i0 + p1) as f64);
                if w0.min(w1) < smax[seg] {
                    let mut x = (i0 + p0) as f64;
                    let mut any = false;
                    for zi in &mut z[off + p0..=off + p1] {
                        let wv = base + gx * x;
                        let lowers = wv < *zi;
                        any |= lowers;
                        *zi = if lowers { wv } else { *zi };
                        x += 1.0;
                    }
                    if any {
                        let s0 = bx * BLOCK;
                        let s1 = (s0 + BLOCK).min(w);
                        smax[seg] = z[off + s0..off + s1]
                            .iter()
                            .fold(f64::NEG_INFINITY, |m, v| m.max(*v));
                        let blk = by * bw + bx;
                        if !written.contains(&blk) {
                            written.push(blk);
                        }
                    }
                }
                p0 = p1 + 1;
            }
        });
        for &blk in written.iter() {
            dirty[blk] = true;
        }
    }
}

impl Tile {
    /// Rasterise the quads of a grid of points ([`Tile::triangle`] with `cull_w`): `ncols`
    /// columns of `nl` points each, column after column; quad (c, i) is the triangles
    /// (a_i, a_i+1, b_i+1) and (a_i, b_i+1, b_i) of columns a = c, b = c + 1. Quads are
    /// taken in groups of [`GROUP`] × [`GROUP`]; a group whose points all lie above `cull_w`
    /// or beyond one side of the tile is skipped whole, since [`cover`] would return at once
    /// on each of its triangles (the same tests, on the group's bounds). The order of the
    /// triangles changes, not the minimum each node keeps.
    pub fn quads(&mut self, pts: &[[f64; 3]], ncols: usize, nl: usize, cull_w: f64) {
        let rect = (self.i0, self.j0, self.w, self.h);
        for c0 in (0..ncols.saturating_sub(1)).step_by(GROUP) {
            let c1 = (c0 + GROUP).min(ncols - 1);
            for i0 in (0..nl.saturating_sub(1)).step_by(GROUP) {
                let i1 = (i0 + GROUP).min(nl - 1);
                let group = (c0..=c1).flat_map(|c| pts[c * nl + i0..=c * nl + i1].iter().copied());
                if misses_all(rect, group, cull_w) {
                    continue;
                }
                for c in c0..c1 {
                    let a = &pts[c * nl..(c + 1) * nl];
                    let b = &pts[(c + 1) * nl..(c + 2) * nl];
                    for i in i0..i1 {
                        self.triangle(a[i], a[i + 1], b[i + 1], cull_w);
                        self.triangle(a[i], b[i + 1], b[i], cull_w);
                    }
                }
            }
        }
    }
}

/// Quads per side of the groups of [`Tile::quads`].
const GROUP: usize = 4;

/// Whether [`cover`] returns at once for a triangle with these vertices: all above
/// `cull_w`, or its box beyond one side of the tile `rect` (the tests `cover` begins with).
#[inline]
fn misses(rect: (usize, usize, usize, usize), v: &[[f64; 3]; 3], cull_w: f64) -> bool {
    misses_all(rect, v.iter().copied(), cull_w)
}

/// [`misses`] for every triangle whose vertices are among `pts` (their bounds are within
/// the bounds of all of them).
#[inline]
fn misses_all(
    rect: (usize, usize, usize, usize),
    pts: impl Iterator<Item = [f64; 3]>,
    cull_w: f64,
) -> bool {
    let (i0, j0, w, h) = rect;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in pts {
        lo = [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let tx0 = i0 as f64;
    let ty0 = j0 as f64;
    let tx1 = (i0 + w) as f64 - 1.0;
    let ty1 = (j0 + h) as f64 - 1.0;
    lo[2] > cull_w
        || hi[0] < tx0 - EPS
        || lo[0] > tx1 + EPS
        || hi[1] < ty0 - EPS
        || lo[1] > ty1 + EPS
}

/// Node rectangle (i0, j0, width, height) of tile `tid`.
pub(crate) fn tile_rect(
    tid: usize,
    t: usize,
    ntx: usize,
    nx: usize,
    ny: usize,
) -> (usize, usize, usize, usize) {
    let i0 = (tid % ntx) * t;
    let j0 = (tid / ntx) * t;
    (i0, j0, t.min(nx - i0), t.min(ny - j0))
}

/// Widen the node-space box `bb` (X0, Y0, X1, Y1) to hold `p`.
pub(crate) fn grow(bb: &mut [f64; 4], p: &[f64; 3]) {
    bb[0] = bb[0].min(p[0]);
    bb[1] = bb[1].min(p[1]);
    bb[2] = bb[2].max(p[0]);
    bb[3] = bb[3].max(p[1]);
}

/// The largest height of block (bx, by), from the row pieces' maxima `smax` (`bw` per row).
fn block_max(smax: &[f64], bw: usize, bx: usize, by: usize) -> f64 {
    let h = smax.len() / bw;
    let mut m = f64::NEG_INFINITY;
    for r in by * BLOCK..((by + 1) * BLOCK).min(h) {
        m = m.max(smax[r * bw + bx]);
    }
    m
}

/// The node columns and rows of the tile that [`cover`] could reach with this triangle
/// (its bounding box widened by the node tolerance), or `None` when it reaches none.
#[inline]
fn reach(
    rect: (usize, usize, usize, usize),
    a: &[f64; 3],
    b: &[f64; 3],
    c: &[f64; 3],
    cull_w: f64,
) -> Option<((usize, usize), (usize, usize))> {
    let (i0, j0, w, h) = rect;
    if a[2].min(b[2]).min(c[2]) > cull_w {
        return None;
    }
    let xmin = a[0].min(b[0]).min(c[0]);
    let xmax = a[0].max(b[0]).max(c[0]);
    let ymin = a[1].min(b[1]).min(c[1]);
    let ymax = a[1].max(b[1]).max(c[1]);
    let (tx0, ty0) = (i0 as f64, j0 as f64);
    let tx1 = (i0 + w) as f64 - 1.0;
    let ty1 = (j0 + h) as f64 - 1.0;
    let mut c0 = ceil_fast(xmin - EPS).max(tx0);
    let mut c1 = floor_fast(xmax + EPS).min(tx1);
    let mut r0 = ceil_fast(ymin - EPS).max(ty0);
    let mut r1 = floor_fast(ymax + EPS).min(ty1);
    // A triangle beyond the tile's columns reaches only the rows where it meets them (the
    // rows `spans` scans), and across the same for columns.
    let v = [*a, *b, *c];
    if xmin < tx0 - SLAB || xmax > tx1 + SLAB {
        let (ylo, yhi) = slab_rows(&v, tx0 - SLAB, tx1 + SLAB)?;
        r0 = r0.max(ceil_fast(ylo - ROW_SLACK));
        r1 = r1.min(floor_fast(yhi + ROW_SLACK));
    }
    if ymin < ty0 - SLAB || ymax > ty1 + SLAB {
        let (xlo, xhi) = slab_cols(&v, ty0 - SLAB, ty1 + SLAB)?;
        c0 = c0.max(ceil_fast(xlo - ROW_SLACK));
        c1 = c1.min(floor_fast(xhi + ROW_SLACK));
    }
    // (Also false for NaN.)
    if c0 <= c1 && r0 <= r1 {
        Some(((c0 as usize, c1 as usize), (r0 as usize, r1 as usize)))
    } else {
        None
    }
}

/// A lower bound of every height [`cover`] gives for the triangle (its lowest vertex less
/// the node tolerance along the plane's slope and the rounding of the plane's evaluation),
/// or `None` for a triangle seen edge-on (which covers nothing).
#[inline]
fn lower_bound(a: &[f64; 3], b: &[f64; 3], c: &[f64; 3]) -> Option<f64> {
    let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    if det.abs() < 1e-12 {
        return None;
    }
    let gx = (e1[2] * e2[1] - e1[1] * e2[2]) / det;
    let gy = (e1[0] * e2[2] - e1[2] * e2[0]) / det;
    let low = a[2].min(b[2]).min(c[2]);
    // Nodes up to the edge tolerance outside the triangle, and the plane's rounding (a few
    // ulp of the magnitudes: far below 1e-13 of them), then the tie allowance.
    let margin = 1e-13 * (1.0 + low.abs()) + 1e-6 * (gx.abs() + gy.abs());
    let v = low - margin + TIE_MM;
    v.is_finite().then_some(v)
}

/// A triangle that could lower no node by more than this is skipped, mm: on a floor that
/// many samples' flat end faces cut at the same height (ties to the last bits), each would
/// otherwise be rasterised to change nothing. A node ends at most 1 pm (1e-6 µm) above
/// the plain minimum over every triangle.
pub(crate) const TIE_MM: f64 = 1e-9;

/// Node tolerance of [`cover`]'s edges.
const EPS: f64 = 1e-9;

/// Every node of the tile rectangle `(i0, j0, w, h)` that the triangle covers, with the
/// triangle's height there: `f(index in the tile, W)`, rows in order, columns ascending.
/// Nothing when its lowest vertex is above `cull_w`.
#[inline]
pub(crate) fn cover(
    rect: (usize, usize, usize, usize),
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    cull_w: f64,
    mut f: impl FnMut(usize, f64),
) {
    let (i0, j0, w, _) = rect;
    spans(rect, a, b, c, cull_w, |row, c0, c1, base, gx| {
        let off = (row - j0) * w;
        let mut x = c0 as f64;
        for i in off + c0 - i0..=off + c1 - i0 {
            f(i, base + gx * x);
            x += 1.0;
        }
    });
}

/// The rows of the tile that the triangle covers, each as `f(row, first column, last
/// column, base, gx)`: the triangle's height at node (column X, row) is `base + gx · X`
/// (X as `f64`), rows in order. Nothing when its lowest vertex is above `cull_w`.
#[inline]
fn spans(
    rect: (usize, usize, usize, usize),
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    cull_w: f64,
    f: impl FnMut(usize, usize, usize, f64, f64),
) {
    spans_of(rect, a, b, c, cull_w, true, f);
}

/// Half-width beyond the tile's outer columns of the slab [`slab_rows`] clips to: twice the
/// node tolerance, so that a row whose crossings reach a column within the tolerance lies
/// within the slab's rows whatever the rounding of the crossings (1e-13 of a node).
const SLAB: f64 = 2.0 * EPS;
/// Rows added on each side of the slab's rows: the vertex band of [`spans`] (`EPS`) and
/// the rounding of the clipped edges' ends, generously.
const ROW_SLACK: f64 = 1e-6;

/// The range of Y of the part of triangle `v` with X in `[x0, x1]` (`None` when it has
/// none): the part is a convex polygon whose corners lie on the triangle's edges clipped
/// to the slab, so their Y bound it.
#[inline]
fn slab_rows(v: &[[f64; 3]; 3], x0: f64, x1: f64) -> Option<(f64, f64)> {
    slab_range::<0, 1>(v, x0, x1)
}

/// [`slab_rows`] across: the range of X of the part of `v` with Y in `[y0, y1]`.
#[inline]
fn slab_cols(v: &[[f64; 3]; 3], y0: f64, y1: f64) -> Option<(f64, f64)> {
    slab_range::<1, 0>(v, y0, y1)
}

/// The range of coordinate `O` of the part of triangle `v` whose coordinate `S` lies in
/// `[s0, s1]`.
#[inline]
fn slab_range<const S: usize, const O: usize>(
    v: &[[f64; 3]; 3],
    s0: f64,
    s1: f64,
) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut edge = |p: &[f64; 3], q: &[f64; 3]| {
        let ds = q[S] - p[S];
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        if ds == 0.0 {
            if p[S] < s0 || p[S] > s1 {
                return;
            }
        } else {
            let (ta, tb) = ((s0 - p[S]) / ds, (s1 - p[S]) / ds);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
            if t0 > t1 {
                return;
            }
        }
        let d = q[O] - p[O];
        let (oa, ob) = (p[O] + t0 * d, p[O] + t1 * d);
        lo = lo.min(oa.min(ob));
        hi = hi.max(oa.max(ob));
    };
    edge(&v[0], &v[1]);
    edge(&v[1], &v[2]);
    edge(&v[2], &v[0]);
    (lo <= hi).then_some((lo, hi))
}

/// [`spans`], with the rows first clipped to those where the triangle meets the tile's
/// columns (`clip`) or not (the plain scan, for tests): the same spans either way.
#[inline]
fn spans_of(
    rect: (usize, usize, usize, usize),
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
    cull_w: f64,
    clip: bool,
    mut f: impl FnMut(usize, usize, usize, f64, f64),
) {
    let (i0, j0, w, h) = rect;
    {
        if a[2].min(b[2]).min(c[2]) > cull_w {
            return;
        }
        let xmin = a[0].min(b[0]).min(c[0]);
        let xmax = a[0].max(b[0]).max(c[0]);
        let ymin = a[1].min(b[1]).min(c[1]);
        let ymax = a[1].max(b[1]).max(c[1]);
        let tx0 = i0 as f64;
        let ty0 = j0 as f64;
        let tx1 = (i0 + w) as f64 - 1.0;
        let ty1 = (j0 + h) as f64 - 1.0;
        if xmax < tx0 - EPS || xmin > tx1 + EPS || ymax < ty0 - EPS || ymin > ty1 + EPS {
            return;
        }
        let (mut ry0, mut ry1) = (
            ceil_fast(ymin - EPS).max(ty0),
            floor_fast(ymax + EPS).min(ty1),
        );
        if clip && (xmin < tx0 - SLAB || xmax > tx1 + SLAB) {
            // Only the rows where the triangle meets the tile's columns.
            let Some((ylo, yhi)) = slab_rows(&[a, b, c], tx0 - SLAB, tx1 + SLAB) else {
                return;
            };
            ry0 = ry0.max(ceil_fast(ylo - ROW_SLACK));
            ry1 = ry1.min(floor_fast(yhi + ROW_SLACK));
        }
        if ry1 < ry0 {
            return;
        }
        let (ry0, ry1) = (ry0 as usize, ry1 as usize);
        // No node column within reach (a triangle smaller than the node spacing): the edge
        // crossings below lie within [xmin, xmax] up to their rounding, `slack`.
        let slack = EPS + 1e-6 + 4.0 * f64::EPSILON * xmin.abs().max(xmax.abs());
        if ceil_fast(xmin - slack) > floor_fast(xmax + slack) {
            return;
        }
        // Plane W = a.W + gx (X − a.X) + gy (Y − a.Y).
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        if det.abs() < 1e-12 {
            return; // seen edge-on: covers no area
        }
        let gx = (e1[2] * e2[1] - e1[1] * e2[2]) / det;
        let gy = (e1[0] * e2[2] - e1[2] * e2[0]) / det;
        let verts = [a, b, c];
        for row in ry0..=ry1 {
            let y = row as f64;
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for k in 0..3 {
                let p = verts[k];
                let q = verts[(k + 1) % 3];
                let (py, qy) = (p[1], q[1]);
                if (py - y) * (qy - y) <= 0.0 {
                    if (qy - py).abs() < 1e-300 {
                        lo = lo.min(p[0].min(q[0]));
                        hi = hi.max(p[0].max(q[0]));
                    } else {
                        let t = ((y - py) / (qy - py)).clamp(0.0, 1.0);
                        let x = p[0] + t * (q[0] - p[0]);
                        lo = lo.min(x);
                        hi = hi.max(x);
                    }
                } else if (py - y).abs() <= EPS || (qy - y).abs() <= EPS {
                    // Within the tolerance band of a vertex.
                    let x = if (py - y).abs() <= EPS { p[0] } else { q[0] };
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
            if lo > hi {
                continue;
            }
            let c0 = ceil_fast(lo - EPS).max(tx0);
            let c1 = floor_fast(hi + EPS).min(tx1);
            if c1 < c0 {
                continue;
            }
            let (c0, c1) = (c0 as usize, c1 as usize);
            let base = a[2] + gy * (y - a[1]) - gx * a[0];
            f(row, c0, c1, base, gx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_of_a_square_leave_no_hole_and_keep_the_plane() {
        let mut t = Tile::new(0, 0, 8, 8);
        // A tilted square from (0.5, 0.5) to (6.3, 5.7): W = 0.1 X + 0.2 Y.
        let p = |x: f64, y: f64| [x, y, 0.1 * x + 0.2 * y];
        let (a, b, c, d) = (p(0.5, 0.5), p(6.3, 0.5), p(6.3, 5.7), p(0.5, 5.7));
        t.triangle(a, b, c, 10.0);
        t.triangle(a, c, d, 10.0);
        for j in 0..8 {
            for i in 0..8 {
                let inside = (1..=6).contains(&i) && (1..=5).contains(&j);
                let z = t.z[j * 8 + i];
                if inside {
                    assert!((z - (0.1 * i as f64 + 0.2 * j as f64)).abs() < 1e-12);
                } else {
                    assert!(z.is_infinite());
                }
            }
        }
    }

    /// The culls (groups of quads, block bounds, row pieces, the tie allowance) change which
    /// triangles and nodes are looked at, not the lowest height beyond the allowance: a grid
    /// of points rasterised with them keeps what the plain minimum over every triangle
    /// keeps, never less and at most [`TIE_MM`] more, in any order; sheets that tie to the
    /// last bits (a floor many flat end faces cut) included.
    #[test]
    fn culled_rasterising_keeps_the_plain_minimum_within_the_tie_allowance() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let rect = (5, 3, 40, 37);
        let mut plain = vec![f64::INFINITY; 40 * 37];
        let mut tile = Tile::new(5, 3, 40, 37);
        for sheet in 0..90 {
            // A wavy sheet of 9 × 7 points over (and beyond) the tile, at a random height;
            // the last 30 flat, at one height give or take a few ulp (ties).
            let oz = if sheet < 60 {
                rnd() * 0.4
            } else {
                0.1 + (rnd() - 0.5) * 1e-15
            };
            let (ox, oy) = (rnd() * 60.0 - 10.0, rnd() * 60.0 - 10.0);
            let (sx, sy) = (1.0 + rnd() * 6.0, 1.0 + rnd() * 6.0);
            let (ncols, nl) = (9, 7);
            let mut pts = Vec::new();
            for c in 0..ncols {
                for i in 0..nl {
                    let (x, y) = (ox + c as f64 * sx, oy + i as f64 * sy + 0.3 * c as f64);
                    let wave = 0.01 * ((x * 0.3).sin() + (y * 0.2).cos()) + 0.002 * x;
                    pts.push([x, y, if sheet < 60 { oz + wave } else { oz }]);
                }
            }
            let cull = 0.3;
            for c in 0..ncols - 1 {
                for i in 0..nl - 1 {
                    let (a0, a1) = (pts[c * nl + i], pts[c * nl + i + 1]);
                    let (b0, b1) = (pts[(c + 1) * nl + i], pts[(c + 1) * nl + i + 1]);
                    for (p, q, r) in [(a0, a1, b1), (a0, b1, b0)] {
                        cover(rect, p, q, r, cull, |k, w| plain[k] = plain[k].min(w));
                    }
                }
            }
            tile.quads(&pts, ncols, nl, cull);
        }
        assert!(plain.iter().any(|z| z.is_finite()));
        let mut exact = 0;
        for (p, t) in plain.iter().zip(&tile.z) {
            if p.is_finite() {
                assert!(*t >= *p && *t - *p <= TIE_MM, "{t} against {p}");
                exact += usize::from(p.to_bits() == t.to_bits());
            } else {
                assert_eq!(p.to_bits(), t.to_bits());
            }
        }
        // Where nothing ties, the minimum is kept bit for bit.
        assert!(exact > plain.len() / 2, "{exact} of {}", plain.len());
    }

    /// Random triangles about a tile: long slivers across it, edges upright or level at
    /// its outer columns and rows give or take the node tolerance and a few ulp, vertices
    /// on rows.
    fn awkward_triangles() -> Vec<[[f64; 3]; 3]> {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (x0, x1, y0, y1) = (5.0, 30.0, 3.0, 60.0);
        let near =
            |v: f64, r: f64| v + [0.0, 1e-9, -1e-9, 2e-9, -2e-9, 1e-13, -1e-13][(r * 7.0) as usize];
        let mut out = Vec::new();
        for n in 0..20_000 {
            let mut p = || [rnd() * 60.0 - 15.0, rnd() * 90.0 - 15.0, rnd()];
            let (mut a, mut b, mut c) = (p(), p(), p());
            match n % 5 {
                // A sliver: c next to b.
                0 => {
                    c = [
                        b[0] + (rnd() - 0.5) * 0.3,
                        b[1] + (rnd() - 0.5) * 0.3,
                        rnd(),
                    ]
                }
                // An upright edge at an outer column.
                1 => {
                    let x = near(if rnd() < 0.5 { x0 } else { x1 }, rnd());
                    a[0] = x;
                    b[0] = near(x, rnd());
                }
                // A level edge at an outer row.
                2 => {
                    let y = near(if rnd() < 0.5 { y0 } else { y1 }, rnd());
                    a[1] = y;
                    b[1] = near(y, rnd());
                }
                // Vertices on rows and columns.
                3 => {
                    for v in [&mut a, &mut b, &mut c] {
                        v[0] = near(v[0].round(), rnd());
                        v[1] = near(v[1].round(), rnd());
                    }
                }
                _ => {}
            }
            out.push([a, b, c]);
        }
        out
    }

    #[test]
    fn clipped_rows_give_the_same_spans_as_the_plain_scan() {
        let rect = (5, 3, 26, 58);
        let mut rows = 0;
        for [a, b, c] in awkward_triangles() {
            let mut clipped = Vec::new();
            let mut plain = Vec::new();
            let key = |r: usize, c0: usize, c1: usize, base: f64, gx: f64| {
                (r, c0, c1, base.to_bits(), gx.to_bits())
            };
            spans_of(rect, a, b, c, 2.0, true, |r, c0, c1, base, gx| {
                clipped.push(key(r, c0, c1, base, gx))
            });
            spans_of(rect, a, b, c, 2.0, false, |r, c0, c1, base, gx| {
                plain.push(key(r, c0, c1, base, gx))
            });
            assert_eq!(clipped, plain, "{a:?} {b:?} {c:?}");
            rows += plain.len();
        }
        assert!(rows > 100_000, "{rows}");
    }

    #[test]
    fn the_reach_holds_every_node_a_triangle_covers() {
        let rect = (5, 3, 26, 58);
        let mut covered = 0;
        for [a, b, c] in awkward_triangles() {
            let got = reach(rect, &a, &b, &c, 2.0);
            spans_of(rect, a, b, c, 2.0, false, |r, c0, c1, _, _| {
                let ((x0, x1), (y0, y1)) = got.expect("a reach");
                assert!((y0..=y1).contains(&r), "row {r} {a:?} {b:?} {c:?}");
                assert!(x0 <= c0 && c1 <= x1, "{c0}..{c1} {a:?} {b:?} {c:?}");
                covered += 1;
            });
        }
        assert!(covered > 100_000, "{covered}");
    }

    #[test]
    fn culled_triangle_leaves_tile_untouched() {
        let mut t = Tile::new(0, 0, 4, 4);
        t.triangle([0.0, 0.0, 5.0], [3.0, 0.0, 5.0], [0.0, 3.0, 5.0], 1.0);
        assert!(t.z.iter().all(|z| z.is_infinite()));
    }
}
