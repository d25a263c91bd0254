//! Traversal stacks: a fixed-size stack with a heap spill for the BVH2 walks (a local of
//! each walk), and for the single-ray walks of the 8-wide tree one stack per thread, grown to
//! the deepest tree seen, which every user borrows ([`STACK`]: the batch walks once per
//! batch, the hybrids once per hand-off).

use super::wide::Bvh8;

/// Fixed-size traversal stack with a heap spill for pathological trees.
pub(super) struct Stack<T: Copy, const N: usize> {
    items: [T; N],
    len: usize,
    spill: Vec<T>,
}

impl<T: Copy + Default, const N: usize> Stack<T, N> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Stack {
            items: [T::default(); N],
            len: 0,
            spill: Vec::new(),
        }
    }
    #[inline(always)]
    pub(super) fn push(&mut self, v: T) {
        if self.len < N {
            self.items[self.len] = v;
            self.len += 1;
        } else {
            self.spill.push(v);
        }
    }
    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<T> {
        if let Some(v) = self.spill.pop() {
            return Some(v);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.items[self.len])
    }
}

/// Traversal stack entries a walk of `bvh` needs: each node level leaves at most 7 entries
/// behind, and a node writes at most 8 slots at once (the closest-hit walk's octant pass
/// writes all of them).
pub(super) fn stack_need(bvh: &Bvh8) -> usize {
    bvh.depth * 7 + 8
}

/// Grow the thread's traversal `stack` to what a walk of `bvh` needs ([`stack_need`]), for
/// every user of [`STACK`].
#[inline(always)]
pub(super) fn grow_stack(stack: &mut Vec<(u32, f32)>, bvh: &Bvh8) {
    let need = stack_need(bvh);
    if stack.len() < need {
        stack.resize(need, (0, 0.0));
    }
}

thread_local! {
    /// Traversal stack of this thread, grown to the deepest tree seen (so a ray allocates
    /// nothing and clears nothing).
    pub(super) static STACK: std::cell::RefCell<Vec<(u32, f32)>> = const { std::cell::RefCell::new(Vec::new()) };
}
