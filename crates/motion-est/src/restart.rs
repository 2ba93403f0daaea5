//! Starting motions for the re-start of an estimate that could not separate the dominant motion
//! — block matching on a tiling of the region, then the affine motions that the most
//! blocks agree on.
//!
//! When a motion covers 35–50 % of the region, the coarse levels see a blur of the two motions
//! and the coarse-to-fine fit settles between them, where no group of pixels fits and the robust
//! weights cannot pull it out (the fit is then flagged unreliable). Small blocks each see mostly
//! one motion: matched separately, within a search window around the failed fit (which lies
//! between the motions present), their displacements fall into a few groups. Each group with
//! enough blocks gives an affine motion by least squares over its blocks, which starts a warm,
//! fine-level fit; the caller keeps the fit explaining most pixels.

use crate::pyramid::Level;
use crate::region::{PixelBox, Region};

/// Side of a matching block, in pixels of the matching level.
const BLOCK: usize = 8;
/// Half-width of the integer search windows, in pixels of the matching level.
const SEARCH: i32 = 7;
/// The matching level is the finest at which the region's box holds at most this many pixels
/// (a 64×64 region is matched at full resolution, a 320×240 frame at half resolution).
const MAX_MATCH_PIXELS: usize = 24_576;
/// A block is kept when its best sum of squared differences is below this share of the mean over
/// the search window (a distinct minimum: not a flat block or a repetitive texture).
const DISTINCT: f64 = 0.5;
/// Blocks within this distance (in pixels of the matching level) of a motion agree with it: about
/// twice the matching error of a textured block, and small enough that a seed halfway between
/// two motions 1.4 px apart (the grid's closest pair) gathers neither.
const AGREE: f64 = 0.4;
/// Starting motions returned at most.
const MAX_STARTS: usize = 3;

/// One block's displacement: the block centre and its displacement, in level-0 pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlockVector {
    c: [f64; 2],
    d: [f64; 2],
}

/// An affine displacement d(r) = t + A (r − origin), level-0 pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Affine {
    /// [t_x, A_xx, A_xy, t_y, A_yx, A_yy], the layout of the affine model.
    pub(crate) a: [f64; 6],
}

impl Affine {
    fn translation(d: [f64; 2]) -> Self {
        Self {
            a: [d[0], 0.0, 0.0, d[1], 0.0, 0.0],
        }
    }

    fn at(&self, x: f64, y: f64) -> [f64; 2] {
        let a = &self.a;
        [a[0] + a[1] * x + a[2] * y, a[3] + a[4] * x + a[5] * y]
    }
}

/// The matching level: the finest level (below `levels`) at which `b` holds at most
/// [`MAX_MATCH_PIXELS`] pixels.
pub(crate) fn matching_level(b: PixelBox, levels: usize) -> usize {
    let (w, h) = (b.i1 + 1 - b.i0, b.j1 + 1 - b.j0);
    (0..levels)
        .find(|&l| (w >> l) * (h >> l) <= MAX_MATCH_PIXELS)
        .unwrap_or(levels.saturating_sub(1))
}

/// Matches the blocks of a tiling of `b` at level `l` (of scale 2^l) that lie inside `region`,
/// each over the integer displacements within ±[`SEARCH`] of each of the `guesses` (level-0
/// pixels, at the block's centre, in level-0 coordinates; the best match over the windows is
/// kept), refined to sub-pixel by a parabola through the sums of squared differences. Blocks
/// whose minimum is on a window's border or not distinct are left out.
pub(crate) fn block_vectors(
    f0: &Level,
    f1: &Level,
    l: usize,
    region: &Region<'_>,
    b: PixelBox,
    guesses: &[&dyn Fn(f64, f64) -> [f64; 2]],
    out: &mut Vec<BlockVector>,
) {
    out.clear();
    let s = (1usize << l) as f64;
    let i_lo = b.i0.div_ceil(1 << l).max(f0.x0);
    let j_lo = b.j0.div_ceil(1 << l).max(f0.y0);
    let i_hi = (b.i1 >> l).min(f0.x0 + f0.width - 1);
    let j_hi = (b.j1 >> l).min(f0.y0 + f0.height - 1);
    let n = (2 * SEARCH + 1) as usize;
    let mut ssd = vec![0.0f64; n * n];
    let mut j = j_lo;
    while j + BLOCK <= j_hi + 1 {
        let mut i = i_lo;
        while i + BLOCK <= i_hi + 1 {
            let (x0, y0) = (i, j);
            i += BLOCK;
            let (x1, y1) = (x0 + BLOCK - 1, y0 + BLOCK - 1);
            let inside = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
                .iter()
                .all(|&(x, y)| region.weight(x as f64 * s, y as f64 * s) > 0.0);
            if !inside {
                continue;
            }
            let c = [
                (x0 as f64 + 0.5 * (BLOCK - 1) as f64) * s,
                (y0 as f64 + 0.5 * (BLOCK - 1) as f64) * s,
            ];
            let mut best: Option<([f64; 2], f64)> = None;
            let mut centres: Vec<(i64, i64)> = Vec::with_capacity(guesses.len());
            for guess in guesses {
                let g = guess(c[0], c[1]);
                if !(g[0].is_finite() && g[1].is_finite()) {
                    continue;
                }
                let g = ((g[0] / s).round() as i64, (g[1] / s).round() as i64);
                if centres.contains(&g) {
                    continue;
                }
                centres.push(g);
                if let Some(m) = match_block(f0, f1, (x0, y0), g, &mut ssd)
                    && best.is_none_or(|b| m.1 < b.1)
                {
                    best = Some(m);
                }
            }
            if let Some((d, _)) = best {
                out.push(BlockVector {
                    c,
                    d: [d[0] * s, d[1] * s],
                });
            }
        }
        j += BLOCK;
    }
}

/// The displacement (level pixels) of the block at `p` of `f0` in `f1`, searched around `g`, and
/// its sum of squared differences.
fn match_block(
    f0: &Level,
    f1: &Level,
    p: (usize, usize),
    g: (i64, i64),
    ssd: &mut [f64],
) -> Option<([f64; 2], f64)> {
    let n = (2 * SEARCH + 1) as usize;
    let (mut best, mut best_k) = (f64::INFINITY, usize::MAX);
    let (mut sum, mut count) = (0.0, 0usize);
    for (k, v) in ssd.iter_mut().enumerate() {
        let dx = g.0 + (k % n) as i64 - i64::from(SEARCH);
        let dy = g.1 + (k / n) as i64 - i64::from(SEARCH);
        *v = block_ssd(f0, f1, p, (dx, dy)).unwrap_or(f64::INFINITY);
        if v.is_finite() {
            sum += *v;
            count += 1;
            if *v < best {
                (best, best_k) = (*v, k);
            }
        }
    }
    if best_k == usize::MAX || count < n * n / 2 || best > DISTINCT * sum / count as f64 {
        return None;
    }
    let (kx, ky) = (best_k % n, best_k / n);
    if kx == 0 || ky == 0 || kx == n - 1 || ky == n - 1 {
        return None;
    }
    // A parabola through the minimum and its two neighbours along each axis.
    let vertex = |a: f64, b: f64, c: f64| {
        let den = a - 2.0 * b + c;
        if den > 0.0 && (a + c).is_finite() {
            (0.5 * (a - c) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    };
    let k = best_k;
    let fx = vertex(ssd[k - 1], ssd[k], ssd[k + 1]);
    let fy = vertex(ssd[k - n], ssd[k], ssd[k + n]);
    Some((
        [
            (g.0 + kx as i64 - i64::from(SEARCH)) as f64 + fx,
            (g.1 + ky as i64 - i64::from(SEARCH)) as f64 + fy,
        ],
        best,
    ))
}

/// Σ (f1(r + d) − f0(r))² over the block at `p`, `None` when it leaves either window.
fn block_ssd(f0: &Level, f1: &Level, p: (usize, usize), d: (i64, i64)) -> Option<f64> {
    let (qx, qy) = (p.0 as i64 + d.0, p.1 as i64 + d.1);
    let b = BLOCK as i64;
    if qx < f1.x0 as i64
        || qy < f1.y0 as i64
        || qx + b > (f1.x0 + f1.width) as i64
        || qy + b > (f1.y0 + f1.height) as i64
        || p.0 < f0.x0
        || p.1 < f0.y0
        || p.0 + BLOCK > f0.x0 + f0.width
        || p.1 + BLOCK > f0.y0 + f0.height
    {
        return None;
    }
    let (ax, ay) = (p.0 - f0.x0, p.1 - f0.y0);
    let (bx, by) = ((qx - f1.x0 as i64) as usize, (qy - f1.y0 as i64) as usize);
    let mut acc = 0.0f32;
    for r in 0..BLOCK {
        let a = &f0.data[(ay + r) * f0.width + ax..][..BLOCK];
        let c = &f1.data[(by + r) * f1.width + bx..][..BLOCK];
        acc += a.iter().zip(c).map(|(u, v)| (v - u) * (v - u)).sum::<f32>();
    }
    Some(f64::from(acc))
}

/// Up to [`MAX_STARTS`] affine motions (about `origin`, level-0 pixels) that the most blocks agree
/// with, each with at least `min_blocks` blocks, best first. Found by consensus from every block's
/// translation: the blocks within 2 × [`AGREE`] level pixels (`scale` = 2^level) of the motion
/// are gathered, the affine motion refitted to them by least squares, and the gathering repeated
/// three times within [`AGREE`]; the motion with most blocks is kept, its blocks are removed, and the search is
/// repeated for the next.
pub(crate) fn starting_motions(
    vectors: &[BlockVector],
    origin: [f64; 2],
    scale: f64,
    min_blocks: usize,
) -> Vec<Affine> {
    let tol = AGREE * scale;
    let mut pool: Vec<BlockVector> = vectors
        .iter()
        .map(|v| BlockVector {
            c: [v.c[0] - origin[0], v.c[1] - origin[1]],
            d: v.d,
        })
        .collect();
    let mut starts = Vec::new();
    let mut members = Vec::new();
    while starts.len() < MAX_STARTS && pool.len() >= min_blocks.max(1) {
        let mut best: Option<(usize, Affine)> = None;
        for seed in &pool {
            let mut m = Affine::translation(seed.d);
            for it in 0..4 {
                // The first gathering is twice as wide: a seed's neighbours on a motion with a
                // linear part differ from its translation by a few tenths of a pixel.
                let t = if it == 0 { 2.0 * tol } else { tol };
                agreeing(&pool, &m, t, &mut members);
                match fit(&pool, &members) {
                    Some(f) => m = f,
                    None => break,
                }
            }
            agreeing(&pool, &m, tol, &mut members);
            let count = members.len();
            if best.as_ref().is_none_or(|b| count > b.0) {
                best = Some((count, m));
            }
        }
        let Some((count, m)) = best else { break };
        if count < min_blocks.max(1) {
            break;
        }
        starts.push(m);
        pool.retain(|v| dist_squared(&m, v) >= tol * tol);
    }
    starts
}

/// The squared distance between the displacement `m` predicts at a block and the block's own
/// (squared: the consensus compares it with a threshold for every pair of blocks, and a square
/// root per pair cost more than the rest of a re-start).
fn dist_squared(m: &Affine, v: &BlockVector) -> f64 {
    let p = m.at(v.c[0], v.c[1]);
    let (dx, dy) = (p[0] - v.d[0], p[1] - v.d[1]);
    dx * dx + dy * dy
}

fn agreeing(pool: &[BlockVector], m: &Affine, tol: f64, out: &mut Vec<usize>) {
    out.clear();
    let t2 = tol * tol;
    out.extend((0..pool.len()).filter(|&k| dist_squared(m, &pool[k]) < t2));
}

/// The least-squares affine motion of the `members` of `pool`; a translation (their mean) when
/// they are too few or too close to a line for the linear part.
fn fit(pool: &[BlockVector], members: &[usize]) -> Option<Affine> {
    if members.is_empty() {
        return None;
    }
    let k = members.len() as f64;
    let mean =
        |f: &dyn Fn(&BlockVector) -> f64| members.iter().map(|&i| f(&pool[i])).sum::<f64>() / k;
    let (cx, cy) = (mean(&|v| v.c[0]), mean(&|v| v.c[1]));
    let (dx, dy) = (mean(&|v| v.d[0]), mean(&|v| v.d[1]));
    // Centred second moments of the positions, and their cross moments with the displacements.
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    let (mut xu, mut yu, mut xv, mut yv) = (0.0, 0.0, 0.0, 0.0);
    for &i in members {
        let v = &pool[i];
        let (x, y) = (v.c[0] - cx, v.c[1] - cy);
        let (u, w) = (v.d[0] - dx, v.d[1] - dy);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        xu += x * u;
        yu += y * u;
        xv += x * w;
        yv += y * w;
    }
    let det = sxx * syy - sxy * sxy;
    let spread = sxx + syy;
    // `det` is NaN-free here (finite inputs), so `<=` also catches a degenerate spread.
    if members.len() < 4 || det <= 1e-6 * spread * spread {
        // A translation about the members' centre.
        return Some(Affine::translation([dx, dy]));
    }
    let a11 = (syy * xu - sxy * yu) / det;
    let a12 = (sxx * yu - sxy * xu) / det;
    let a21 = (syy * xv - sxy * yv) / det;
    let a22 = (sxx * yv - sxy * xv) / det;
    Some(Affine {
        a: [
            dx - a11 * cx - a12 * cy,
            a11,
            a12,
            dy - a21 * cx - a22 * cy,
            a21,
            a22,
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_motions_give_two_starts_largest_first() {
        // 60 blocks follow an affine motion, 30 a translation; the largest group comes first and
        // is recovered exactly (its blocks agree to the last digit).
        let truth = Affine {
            a: [3.0, 0.03, -0.035, -2.0, 0.035, 0.03],
        };
        let mut v = Vec::new();
        for k in 0..90 {
            let c = [(k % 10) as f64 * 8.0 - 36.0, (k / 10) as f64 * 8.0 - 36.0];
            let d = if k % 3 == 2 {
                [7.0, 1.0]
            } else {
                truth.at(c[0], c[1])
            };
            v.push(BlockVector { c, d });
        }
        let starts = starting_motions(&v, [0.0, 0.0], 1.0, 4);
        assert_eq!(starts.len(), 2, "{starts:?}");
        for (a, b) in starts[0].a.iter().zip(&truth.a) {
            assert!((a - b).abs() < 1e-9, "{starts:?}");
        }
        let t = starts[1].at(0.0, 0.0);
        assert!(
            (t[0] - 7.0).abs() < 1e-9 && (t[1] - 1.0).abs() < 1e-9,
            "{starts:?}"
        );
    }
}
