//! A bounded log of what a run was fed, for the computations done after the run (fit quality,
//! validation, identifiability): a live feed of any length holds constant memory.
//!
//! [`SampleLog`] keeps at most `limit` items, in whole blocks of `block` consecutive items.
//! When the limit is reached every second kept block is dropped, and from then on only every
//! `stride`-th block is kept (the stride doubles each time), so what is kept covers the whole
//! run evenly, not only its beginning, and each kept block keeps its item-to-item structure.
//! The log also numbers segments (stretches of consecutive items: a kept block after skipped
//! ones, or a gap the caller reports with [`SampleLog::new_segment`]), so lagged sums over the
//! kept items need not cross from one to the next.
//!
//! With `block = 1` this is plain decimation by two: the kept items are those whose index is a
//! multiple of the final stride. With `limit` a power of two (and a multiple of `block`) the
//! vector's capacity never exceeds `limit`: the log decimates before it would grow past it.

/// A bounded, block-decimated log of items (module doc). Used for the replay's fed samples
/// (`crate::results::MAX_FIT_SAMPLES`, blocks of 1) and the validation's regressors
/// (`crate::replay::prediction::Recorder`, 65,536 in blocks of 1,024).
#[derive(Debug, Clone)]
pub struct SampleLog<T> {
    items: Vec<T>,
    /// Segment number of each kept item.
    segments: Vec<usize>,
    /// Segment number of the next item.
    segment: usize,
    limit: usize,
    block: usize,
    /// Items offered.
    pushed: usize,
    /// Blocks offered per block kept (≥ 1).
    stride: usize,
    /// Items offered and not kept.
    dropped: usize,
}

impl<T> SampleLog<T> {
    /// An empty log keeping at most `limit` items in blocks of `block` (≥ 1) consecutive
    /// items. `limit` is raised to two blocks if smaller and lowered to a whole number of
    /// blocks, so that every decimation drops whole blocks.
    pub fn new(limit: usize, block: usize) -> Self {
        let block = block.max(1);
        let limit = limit.max(2 * block) / block * block;
        Self {
            items: Vec::new(),
            segments: Vec::new(),
            segment: 0,
            limit,
            block,
            pushed: 0,
            stride: 1,
            dropped: 0,
        }
    }

    /// Offers one item, decimating as described in the module doc.
    pub fn push(&mut self, item: T) {
        self.push_with(|| item);
    }

    /// Offers one item made by `make`, called only if the item is kept (so a dropped item
    /// costs nothing to build). Returns whether it was kept.
    pub fn push_with(&mut self, make: impl FnOnce() -> T) -> bool {
        let block = self.pushed / self.block;
        let block_start = self.pushed.is_multiple_of(self.block);
        self.pushed += 1;
        if !block.is_multiple_of(self.stride) {
            self.dropped += 1;
            return false;
        }
        if self.items.len() >= self.limit {
            self.decimate();
            if !block.is_multiple_of(self.stride) {
                self.dropped += 1;
                return false;
            }
        }
        // A kept block after skipped ones is not contiguous with the previous kept item.
        if block_start && self.stride > 1 {
            self.new_segment();
        }
        self.items.push(make());
        self.segments.push(self.segment);
        true
    }

    /// Drops every second kept block (all kept blocks are whole: the log is full) and doubles
    /// the stride; the blocks left, no longer adjacent, become separate segments.
    fn decimate(&mut self) {
        let b = self.block;
        let before = self.items.len();
        let keep = |k: usize| (k / b).is_multiple_of(2);
        let mut k = 0;
        self.items.retain(|_| (keep(k), k += 1).0);
        k = 0;
        self.segments.retain(|_| (keep(k), k += 1).0);
        // Renumber: a new segment wherever the old segment or the block changes.
        let mut seg = 0;
        let mut prev: Option<(usize, usize)> = None;
        for (k, s) in self.segments.iter_mut().enumerate() {
            let key = (*s, k / b);
            if prev.is_some_and(|p| p != key) {
                seg += 1;
            }
            prev = Some(key);
            *s = seg;
        }
        self.segment = seg;
        self.dropped += before - self.items.len();
        self.stride *= 2;
    }

    /// A new segment starts (a gap, e.g. between manoeuvres): the next kept item is not
    /// contiguous with the last one.
    pub fn new_segment(&mut self) {
        if self.segments.last() == Some(&self.segment) {
            self.segment += 1;
        }
    }

    /// The kept items, in the order offered.
    pub fn items(&self) -> &[T] {
        &self.items
    }

    /// The segment number of each kept item (non-decreasing; equal numbers: same segment).
    pub fn segments(&self) -> &[usize] {
        &self.segments
    }

    /// Items kept.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether no item was kept.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Items offered and not kept.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// Blocks offered per block kept (1 until the first decimation; with `block = 1`, items
    /// offered per item kept).
    pub fn stride(&self) -> usize {
        self.stride
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks of 1: at most `limit` kept, the kept items are every `stride`-th one, and with a
    /// power-of-two limit the allocation never exceeds it either.
    #[test]
    fn analytic_single_items_are_bounded_and_evenly_decimated() {
        let mut log = SampleLog::new(10, 1);
        for k in 0..1000usize {
            log.push(k);
            assert!(log.len() <= 10);
        }
        assert!(log.stride() >= 100 && log.len() >= 5, "{} {}", log.stride(), log.len());
        for (j, k) in log.items().iter().enumerate() {
            assert_eq!(*k, j * log.stride());
        }
        assert_eq!(log.len() + log.dropped(), 1000);
        let mut log = SampleLog::new(16, 1);
        for k in 0..1000usize {
            log.push(k);
            assert!(log.items.capacity() <= 16, "{}", log.items.capacity());
        }
    }

    /// Blocks of 4, limit 16 (4 blocks): after 70 items (blocks 0 … 17) the decimations at
    /// blocks 4, 8 and 16 leave stride 8 and the kept items are the blocks whose index is a
    /// multiple of it (0, 8, 16), each its own segment; several gap reports in a row make one
    /// boundary; `limit` is rounded to whole blocks.
    #[test]
    fn analytic_blocks_are_kept_whole_and_segmented() {
        let mut log = SampleLog::new(16, 4);
        for k in 0..70usize {
            log.push(k);
        }
        let stride = log.stride();
        assert_eq!(stride, 8);
        let expected: Vec<usize> =
            (0..70usize).filter(|k| (k / 4).is_multiple_of(stride)).collect();
        assert_eq!(log.items(), &expected[..]);
        assert!(log.len() <= 16);
        assert_eq!(log.len() + log.dropped(), 70);
        for (j, s) in log.segments().iter().enumerate() {
            assert_eq!(*s, j / 4, "one segment per kept block");
        }
        let mut log = SampleLog::new(3, 2);
        for k in 0..3usize {
            log.push(k);
            log.new_segment();
            log.new_segment();
        }
        assert_eq!(log.segments(), &[0, 1, 2], "a gap is one boundary, however reported");
        assert_eq!(SampleLog::<u8>::new(7, 2).limit, 6);
        assert_eq!(SampleLog::<u8>::new(1, 1).limit, 2);
    }
}
