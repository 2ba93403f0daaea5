//! Per-estimate buffers, the region's row spans and their bands for concurrent work.

use crate::pyramid::Pyramid;

/// One cell of the covariance's dense grid (see `meat`): the parameters' channels, unused lanes
/// zero.
pub(crate) type Cell = [f32; 8];

/// Per-estimate scratch buffers. Reuse one across estimates to avoid allocation.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    /// Per listed pixel (see `collect`): its index in the first frame's level window.
    pub(super) idx: Vec<u32>,
    /// Its region weight.
    pub(super) m: Vec<f32>,
    /// Its displaced frame difference under the current parameters.
    pub(super) res: Vec<f32>,
    /// The Jacobian's image gradient (the first frame's, mapped through (I + D)^−T; averaged with
    /// the second frame's at coarse levels).
    pub(super) gx: Vec<f32>,
    pub(super) gy: Vec<f32>,
    /// Fractional offsets of its second-frame sample.
    pub(super) fx: Vec<f32>,
    pub(super) fy: Vec<f32>,
    /// Flat index of its sample's top-left tap in the second frame's level window.
    pub(super) qi: Vec<u32>,
    /// Integer sample positions of the listed pixels, for the covariance grids.
    pub(super) pos: Vec<(u32, u32)>,
    /// The covariance's vectors u = m E[ψ'] J (see `UVectors`).
    pub(super) u: Vec<[f32; 8]>,
    /// 0: the sample fell outside the second frame; otherwise valid (at full resolution, 2 where
    /// it was interpolated bicubically and 1 on the bilinear border).
    pub(super) valid: Vec<u8>,
    /// Scratch for the robust scale's selections.
    pub(super) scratch: Vec<f32>,
    /// Runs of consecutive region pixels on one row, from `collect`.
    pub(super) spans: Vec<Span>,
    /// The spans cut into bands for concurrent processing of large regions.
    pub(super) bands: Vec<Band>,
    /// Per span, the range of sample rows of its valid pixels (for the covariance grid's bands).
    pub(super) span_rows: Vec<(u32, u32)>,
    /// Per band of the covariance's dense grid: its cells and a convolution buffer.
    pub(super) grids: Vec<(Vec<Cell>, Vec<Cell>)>,
}

/// A run of `len` consecutive region pixels on level row `j` from column `i0`, stored from entry
/// `k0` of the workspace's per-pixel arrays.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Span {
    pub(crate) j: usize,
    pub(crate) i0: usize,
    pub(crate) len: usize,
    pub(crate) k0: usize,
}

impl Workspace {
    /// Empty buffers, grown on first use.
    pub fn new() -> Self {
        Self::default()
    }
}

/// The two frames' pyramids and the workspace, for single-region use.
#[derive(Debug, Clone, Default)]
pub struct FrameBuffers {
    /// Pyramid of the first frame.
    pub pyramid0: Pyramid,
    /// Pyramid of the second frame.
    pub pyramid1: Pyramid,
    /// Scratch buffers.
    pub workspace: Workspace,
}

impl Workspace {
    /// Cuts the spans into bands of consecutive spans holding at least [`BAND_PIXELS`] pixels
    /// each (the last one may hold fewer). The cut depends only on the region's pixels.
    pub(super) fn make_bands(&mut self) {
        self.bands.clear();
        let mut start = 0;
        for (i, sp) in self.spans.iter().enumerate() {
            let k1 = sp.k0 + sp.len;
            let k0 = self.spans[start].k0;
            if k1 - k0 >= BAND_PIXELS || i + 1 == self.spans.len() {
                self.bands.push(Band {
                    s0: start,
                    s1: i + 1,
                    k0,
                    k1,
                });
                start = i + 1;
            }
        }
    }

    /// Whether the region is large enough (more than one band) for the bands to be processed
    /// concurrently. Small regions stay on one thread without touching the pool.
    pub(super) fn parallel(&self) -> bool {
        cfg!(feature = "parallel") && self.bands.len() > 1
    }
}

/// Pixels per band: large regions are cut into bands of whole row spans of at least this many
/// pixels, which are processed concurrently with the `parallel` feature (see [`Band`]).
pub(super) const BAND_PIXELS: usize = 8192;

/// Consecutive spans `s0..s1` of the region, holding pixels `k0..k1`. The cut depends only on the
/// region (never on the number of threads), and every per-band partial sum is combined in band
/// order, so results are bit-identical whether bands run in parallel or not.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Band {
    pub(super) s0: usize,
    pub(super) s1: usize,
    pub(super) k0: usize,
    pub(super) k1: usize,
}

/// Runs `f` on a thread of rayon's pool when the work is `large` (and the `parallel` feature is
/// on) and the caller is not already one: the bands of a large region are then forked from a
/// pool thread, which the other threads steal from while still spinning, instead of each fork
/// being injected from outside and the caller sleeping until it is done (one cross-thread handoff
/// per fork). The result does not depend on where `f` runs.
pub(super) fn on_pool<R: Send>(large: bool, f: impl FnOnce() -> R + Send) -> R {
    #[cfg(feature = "parallel")]
    if large && rayon::current_thread_index().is_none() {
        return rayon::scope(|_| f());
    }
    let _ = large;
    f()
}

/// `f` over `items` in order: concurrently on rayon's pool with the `parallel` feature (and more
/// than one item), sequentially otherwise. The results come back in the items' order.
pub(super) fn map_bands<I: Send, T: Send>(
    items: Vec<I>,
    f: impl Fn(I) -> T + Sync + Send,
) -> Vec<T> {
    #[cfg(feature = "parallel")]
    if items.len() > 1 {
        use rayon::prelude::*;
        return items.into_par_iter().map(f).collect();
    }
    items.into_iter().map(f).collect()
}
