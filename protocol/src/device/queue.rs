//! Outbound frame queue: a byte ring holding whole encoded frames.

/// Fixed-capacity FIFO of encoded frames, stored back to back in a ring of `CAP` bytes.
///
/// Policy: a frame goes in whole or not at all ([`FrameQueue::push_frame`] returns `false` and
/// the caller counts the drop); nothing already queued is ever overwritten, and nothing blocks.
/// The reader takes bytes in any chunk size ([`FrameQueue::peek`] + [`FrameQueue::consume`],
/// or [`FrameQueue::pop_into`]): the wire is a byte stream and every queued frame ends with its
/// 0x00, so partial writes by a UART/USB driver are fine.
#[derive(Debug, Clone)]
pub struct FrameQueue<const CAP: usize> {
    buf: [u8; CAP],
    /// Index of the oldest byte.
    head: usize,
    /// Bytes queued.
    len: usize,
}

impl<const CAP: usize> Default for FrameQueue<CAP> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize> FrameQueue<CAP> {
    /// An empty queue.
    pub const fn new() -> Self {
        Self {
            buf: [0; CAP],
            head: 0,
            len: 0,
        }
    }

    /// Bytes waiting to be sent.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing waits.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes that can still be queued.
    pub fn free(&self) -> usize {
        CAP - self.len
    }

    /// Queues `frame` if it fits while leaving `reserve` bytes free (to keep room for
    /// higher-priority frames); returns whether it was queued.
    pub fn push_frame(&mut self, frame: &[u8], reserve: usize) -> bool {
        if frame.len().saturating_add(reserve) > self.free() {
            return false;
        }
        let tail = (self.head + self.len) % CAP.max(1);
        let first = frame.len().min(CAP - tail);
        let (a, b) = frame.split_at(first);
        self.buf[tail..tail + a.len()].copy_from_slice(a);
        self.buf[..b.len()].copy_from_slice(b);
        self.len += frame.len();
        true
    }

    /// The oldest queued bytes that are contiguous in memory (possibly not all of them).
    pub fn peek(&self) -> &[u8] {
        let end = (self.head + self.len).min(CAP);
        &self.buf[self.head..end]
    }

    /// Removes `n` bytes (clamped to [`FrameQueue::len`]) from the front, after sending them.
    pub fn consume(&mut self, n: usize) {
        let n = n.min(self.len);
        self.len -= n;
        self.head = if self.len == 0 {
            0
        } else {
            (self.head + n) % CAP
        };
    }

    /// Moves as many queued bytes as fit into `out`; returns how many.
    pub fn pop_into(&mut self, out: &mut [u8]) -> usize {
        let mut copied = 0;
        while copied < out.len() && !self.is_empty() {
            let chunk = self.peek();
            let n = chunk.len().min(out.len() - copied);
            out[copied..copied + n].copy_from_slice(&chunk[..n]);
            copied += n;
            self.consume(n);
        }
        copied
    }

    /// Drops everything queued.
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_frames_or_nothing() {
        let mut q = FrameQueue::<10>::new();
        assert!(q.push_frame(&[1, 2, 3, 0], 0));
        assert!(q.push_frame(&[4, 5, 6, 0], 0));
        assert!(!q.push_frame(&[7, 8, 9, 0], 0)); // 8 + 4 > 10: dropped whole
        assert_eq!(q.len(), 8);
        assert!(!q.push_frame(&[7, 0], 1)); // would eat into the reserve
        assert!(q.push_frame(&[7, 0], 0));
        let mut out = [0u8; 16];
        assert_eq!(q.pop_into(&mut out), 10);
        assert_eq!(&out[..10], &[1, 2, 3, 0, 4, 5, 6, 0, 7, 0]);
        assert!(q.is_empty());
    }

    #[test]
    fn wraps_around_and_partial_reads_keep_order() {
        let mut q = FrameQueue::<8>::new();
        let mut received = heapless::Vec::<u8, 64>::new();
        let mut next = 1u8;
        for _ in 0..20 {
            let frame = [next, next.wrapping_add(1), 0];
            if q.push_frame(&frame, 0) {
                next = next.wrapping_add(2);
            }
            // Read 2 bytes at a time, like a slow driver.
            let chunk = q.peek();
            let n = chunk.len().min(2);
            received.extend_from_slice(&chunk[..n]).unwrap();
            q.consume(n);
        }
        let mut rest = [0u8; 8];
        let n = q.pop_into(&mut rest);
        received.extend_from_slice(&rest[..n]).unwrap();
        // Every frame arrived whole and in order.
        let mut expected = heapless::Vec::<u8, 64>::new();
        let mut v = 1u8;
        while v < next {
            expected.extend_from_slice(&[v, v + 1, 0]).unwrap();
            v += 2;
        }
        assert_eq!(received, expected);
    }

    #[test]
    fn zero_capacity_never_panics() {
        let mut q = FrameQueue::<0>::new();
        assert!(!q.push_frame(&[0], 0));
        assert!(q.push_frame(&[], 0));
        assert_eq!(q.peek(), &[] as &[u8]);
        q.consume(5);
        assert_eq!(q.pop_into(&mut [0u8; 4]), 0);
    }
}
