//! [`EdgeQueue`]: the edges path consistency still has to process, lightest first.
//!
//! GQR's order: an edge's key is the weight of its set (the sum of its relations' weights), and
//! a re-queued edge whose set shrank moves forward (decrease-key). Processing the most
//! constrained edges first propagates the strongest information first and finds a
//! contradiction sooner; the fixpoint does not depend on the order. Ties go to the lower
//! edge, so the order — and the contradiction reported — is the same on every run.

/// An indexed binary min-heap of edges `i · n + j` keyed by weight.
#[derive(Debug, Clone)]
pub(crate) struct EdgeQueue {
    /// `(key, edge)`, a min-heap on the pair.
    heap: Vec<(u32, u32)>,
    /// The heap position of each edge, `u32::MAX` when absent.
    position: Vec<u32>,
}

const ABSENT: u32 = u32::MAX;

impl EdgeQueue {
    pub(crate) fn new(edges: usize) -> Self {
        Self {
            heap: Vec::new(),
            position: vec![ABSENT; edges],
        }
    }

    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// Adds `edge` with `key`, or lowers its key if it is queued with a larger one.
    pub(crate) fn push(&mut self, edge: usize, key: u32) {
        let e = edge as u32;
        let at = self.position[edge];
        let i = if at == ABSENT {
            self.heap.push((key, e));
            self.heap.len() - 1
        } else {
            let i = at as usize;
            if self.heap[i].0 <= key {
                return;
            }
            self.heap[i].0 = key;
            i
        };
        self.position[edge] = i as u32;
        self.sift_up(i);
    }

    /// The lightest edge.
    pub(crate) fn pop(&mut self) -> Option<usize> {
        let top = *self.heap.first()?;
        let last = self.heap.len() - 1;
        self.heap.swap(0, last);
        self.heap.pop();
        self.position[top.1 as usize] = ABSENT;
        if !self.heap.is_empty() {
            self.position[self.heap[0].1 as usize] = 0;
            self.sift_down(0);
        }
        Some(top.1 as usize)
    }

    /// Empties the queue.
    pub(crate) fn clear(&mut self) {
        for (_, e) in self.heap.drain(..) {
            self.position[e as usize] = ABSENT;
        }
    }

    fn sift_up(&mut self, mut i: usize) {
        while i > 0 {
            let parent = (i - 1) / 2;
            if self.heap[parent] <= self.heap[i] {
                break;
            }
            self.swap(i, parent);
            i = parent;
        }
    }

    fn sift_down(&mut self, mut i: usize) {
        let len = self.heap.len();
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut least = i;
            if l < len && self.heap[l] < self.heap[least] {
                least = l;
            }
            if r < len && self.heap[r] < self.heap[least] {
                least = r;
            }
            if least == i {
                break;
            }
            self.swap(i, least);
            i = least;
        }
    }

    fn swap(&mut self, a: usize, b: usize) {
        self.heap.swap(a, b);
        self.position[self.heap[a].1 as usize] = a as u32;
        self.position[self.heap[b].1 as usize] = b as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_lightest_first_with_ties_by_edge_and_keys_only_decrease() {
        let mut q = EdgeQueue::new(10);
        for (e, k) in [(3, 5), (1, 7), (4, 5), (2, 9), (7, 1)] {
            q.push(e, k);
        }
        q.push(2, 2); // lowered
        q.push(7, 8); // a larger key is ignored
        let mut order = Vec::new();
        while let Some(e) = q.pop() {
            order.push(e);
        }
        assert_eq!(order, [7, 2, 3, 4, 1]);
        q.push(5, 1);
        q.clear();
        assert!(q.is_empty());
        q.push(5, 3);
        assert_eq!(q.pop(), Some(5));
    }
}
