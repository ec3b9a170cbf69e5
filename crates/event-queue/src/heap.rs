//! The binary-heap baseline: O(log n) push and pop, nothing to tune.
//!
//! Also used inside [`BoundedQueue`](crate::BoundedQueue) to fine-sort the bucket being consumed
//! (Paul's "binary tree" for the current interval).

use crate::order::Entry;
use crate::{Event, EventQueue, QueueError, check_time};

/// A binary min-heap of entries in the crate's total order (time, then sequence).
#[derive(Clone, Debug)]
pub(crate) struct MinHeap<P> {
    v: Vec<Entry<P>>,
}

impl<P> MinHeap<P> {
    pub(crate) const fn new() -> Self {
        Self { v: Vec::new() }
    }

    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.v.len()
    }

    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.v.is_empty()
    }

    #[inline]
    pub(crate) fn peek(&self) -> Option<&Entry<P>> {
        self.v.first()
    }

    #[inline]
    pub(crate) fn push(&mut self, e: Entry<P>) {
        self.v.push(e);
        self.sift_up(self.v.len() - 1);
    }

    /// Removes the earliest entry. Moves the last leaf to the root and lets it fall to the bottom
    /// along the smaller children before sifting it back up: one comparison per level on the way
    /// down instead of two, since a leaf almost always belongs near the bottom.
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<Entry<P>> {
        let last = self.v.pop()?;
        if self.v.is_empty() {
            return Some(last);
        }
        let top = std::mem::replace(&mut self.v[0], last);
        self.sift_down_to_bottom();
        Some(top)
    }

    /// Keeps the entries whose payload passes `keep`; returns how many were removed.
    pub(crate) fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        let before = self.v.len();
        self.v.retain(|e| keep(&e.payload));
        let removed = before - self.v.len();
        if removed > 0 {
            self.heapify();
        }
        removed
    }

    /// Takes `entries` in bulk (O(n) heap construction when the heap is empty).
    pub(crate) fn extend(&mut self, entries: &mut Vec<Entry<P>>) {
        if self.v.is_empty() {
            std::mem::swap(&mut self.v, entries);
            self.heapify();
        } else {
            for e in entries.drain(..) {
                self.push(e);
            }
        }
    }

    pub(crate) fn clear(&mut self) {
        self.v.clear();
    }

    pub(crate) fn drain(&mut self) -> std::vec::Drain<'_, Entry<P>> {
        self.v.drain(..)
    }

    fn heapify(&mut self) {
        let n = self.v.len();
        for i in (0..n / 2).rev() {
            self.sift_down(i);
        }
    }

    #[inline]
    fn sift_up(&mut self, mut pos: usize) {
        while pos > 0 {
            let parent = (pos - 1) / 2;
            if self.v[pos].before(&self.v[parent]) {
                self.v.swap(pos, parent);
                pos = parent;
            } else {
                break;
            }
        }
    }

    fn sift_down(&mut self, mut pos: usize) {
        let n = self.v.len();
        loop {
            let left = 2 * pos + 1;
            if left >= n {
                break;
            }
            let right = left + 1;
            let child = if right < n && self.v[right].before(&self.v[left]) {
                right
            } else {
                left
            };
            if self.v[child].before(&self.v[pos]) {
                self.v.swap(pos, child);
                pos = child;
            } else {
                break;
            }
        }
    }

    #[inline]
    fn sift_down_to_bottom(&mut self) {
        let n = self.v.len();
        let mut pos = 0;
        let mut child = 1;
        while child + 1 < n {
            if self.v[child + 1].before(&self.v[child]) {
                child += 1;
            }
            self.v.swap(pos, child);
            pos = child;
            child = 2 * pos + 1;
        }
        if child + 1 == n {
            self.v.swap(pos, child);
            pos = child;
        }
        self.sift_up(pos);
    }
}

/// A priority queue of timed events on a binary heap.
///
/// O(log n) per push and pop; the baseline the bounded queue is measured against, and the better
/// choice for small queues or event times with no typical scale.
///
/// ```
/// use event_queue::{EventQueue, HeapQueue};
///
/// let mut q = HeapQueue::new();
/// q.push(2.0, "later").unwrap();
/// q.push(1.0, "sooner").unwrap();
/// q.push(2.0, "later, pushed second").unwrap();
/// assert_eq!(q.pop().unwrap().payload, "sooner");
/// assert_eq!(q.pop().unwrap().payload, "later"); // equal times: first in, first out
/// assert_eq!(q.pop().unwrap().payload, "later, pushed second");
/// assert!(q.pop().is_none());
/// ```
#[derive(Clone, Debug)]
pub struct HeapQueue<P> {
    heap: MinHeap<P>,
    next_seq: u64,
}

impl<P> HeapQueue<P> {
    /// An empty queue.
    pub const fn new() -> Self {
        Self {
            heap: MinHeap::new(),
            next_seq: 0,
        }
    }
}

impl<P> Default for HeapQueue<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<P> EventQueue for HeapQueue<P> {
    type Payload = P;

    #[inline]
    fn push(&mut self, time: f64, payload: P) -> Result<(), QueueError> {
        check_time(time)?;
        let seq = self.next_seq;
        self.next_seq += 1;
        self.heap.push(Entry { time, seq, payload });
        Ok(())
    }

    #[inline]
    fn pop(&mut self) -> Option<Event<P>> {
        self.heap.pop().map(Event::from)
    }

    fn peek(&self) -> Option<(f64, &P)> {
        self.heap.peek().map(|e| (e.time, &e.payload))
    }

    fn len(&self) -> usize {
        self.heap.len()
    }

    fn clear(&mut self) {
        self.heap.clear();
    }

    fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        self.heap.retain(keep)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_sorted_with_fifo_ties() {
        let mut q = HeapQueue::new();
        let times = [3.0, 1.0, 2.0, 1.0, -0.0, 0.0, 5.0, 2.0];
        for (i, &t) in times.iter().enumerate() {
            q.push(t, i).unwrap();
        }
        let order: Vec<usize> = std::iter::from_fn(|| q.pop().map(|e| e.payload)).collect();
        assert_eq!(order, vec![4, 5, 1, 3, 2, 7, 0, 6]);
    }

    #[test]
    fn retain_keeps_heap_order() {
        let mut q = HeapQueue::new();
        for i in 0..100u32 {
            q.push(f64::from((i * 37) % 100), i).unwrap();
        }
        assert_eq!(q.retain(&mut |p| p % 3 != 0), 34);
        let mut last = f64::NEG_INFINITY;
        while let Some(e) = q.pop() {
            assert!(e.payload % 3 != 0);
            assert!(e.time >= last);
            last = e.time;
        }
    }
}
