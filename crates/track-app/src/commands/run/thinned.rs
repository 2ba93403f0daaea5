//! Keeping an evenly spaced subset of a sequence of unknown length in bounded memory.

/// Keeps the items whose index is a multiple of a stride; when more than `cap` are kept, every
/// other one is dropped and the stride doubled. So at most `cap` items are held, evenly spaced,
/// whatever the length (an animated GIF of a stream, a report's strip of frames).
#[derive(Debug, Clone)]
pub struct Thinned<T> {
    items: Vec<(usize, T)>,
    stride: usize,
    cap: usize,
    /// Keep the stride and stop at `cap` items instead of thinning ([`Thinned::truncating`]).
    truncate: bool,
}

impl<T> Thinned<T> {
    /// Keeps at most `cap` items (at least 2), starting with every `stride`-th (at least 1). With
    /// a known length `n`, `stride = n.div_ceil(cap)` never needs thinning.
    pub fn new(cap: usize, stride: usize) -> Self {
        Self {
            items: Vec::new(),
            stride: stride.max(1),
            cap: cap.max(2),
            truncate: false,
        }
    }

    /// Keeps every `stride`-th item (at least 1) until `cap` items (at least 1) are kept, and
    /// none after: a fixed stride asked for by the user, which is never changed.
    pub fn truncating(cap: usize, stride: usize) -> Self {
        Self {
            items: Vec::new(),
            stride: stride.max(1),
            cap: cap.max(1),
            truncate: true,
        }
    }

    /// Whether item `k` would be kept now (to skip building items that would be dropped).
    pub fn wants(&self, k: usize) -> bool {
        k.is_multiple_of(self.stride) && !(self.truncate && self.items.len() >= self.cap)
    }

    /// Offers item `k` (indices increase from 0).
    pub fn push(&mut self, k: usize, item: T) {
        if !self.wants(k) {
            return;
        }
        self.items.push((k, item));
        if !self.truncate && self.items.len() > self.cap {
            let stride = 2 * self.stride;
            self.items.retain(|(i, _)| i.is_multiple_of(stride));
            self.stride = stride;
        }
    }

    /// The current stride: one kept item every `stride` items.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// The kept items with their indices.
    pub fn into_items(self) -> Vec<(usize, T)> {
        self.items
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_at_most_cap_evenly_spaced() {
        for n in [0, 1, 5, 150, 151, 1000, 12_345] {
            let mut t = Thinned::new(150, 1);
            for k in 0..n {
                t.push(k, k);
            }
            let stride = t.stride();
            let items = t.into_items();
            assert!(items.len() <= 150, "{n}");
            assert_eq!(items.len(), n.div_ceil(stride), "{n}");
            assert!(
                items
                    .iter()
                    .enumerate()
                    .all(|(i, &(k, v))| k == i * stride && v == k)
            );
        }
    }

    #[test]
    fn a_truncating_subset_keeps_its_stride_and_stops_at_cap() {
        let mut t = Thinned::truncating(4, 3);
        for k in 0..100 {
            t.push(k, k);
        }
        assert_eq!(t.stride(), 3);
        let ks: Vec<usize> = t.into_items().into_iter().map(|(k, _)| k).collect();
        assert_eq!(ks, vec![0, 3, 6, 9]);
        let mut short = Thinned::truncating(150, 2);
        for k in 0..7 {
            short.push(k, ());
        }
        assert_eq!(short.into_items().len(), 4);
    }

    #[test]
    fn known_length_keeps_the_fixed_stride() {
        let n: usize = 1000;
        let mut t = Thinned::new(150, n.div_ceil(150));
        for k in 0..n {
            t.push(k, ());
        }
        assert_eq!(t.stride(), 7);
        assert_eq!(t.into_items().len(), 143);
    }
}
