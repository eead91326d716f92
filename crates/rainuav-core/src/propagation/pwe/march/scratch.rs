//! The marcher's scratch space: one set of buffers a thread, and the field's pointer for the
//! column pass.

use std::sync::{Mutex, MutexGuard};

use super::super::C32;

/// Raw pointer to the field shared by the column pass, whose threads touch disjoint columns.
#[derive(Clone, Copy)]
pub(super) struct FieldPtr(pub(super) *mut C32);
// SAFETY: used only in `column_pass`, where every task reads and writes a disjoint set of
// columns of the field and nothing else borrows the field meanwhile.
#[allow(unsafe_code)]
unsafe impl Send for FieldPtr {}
#[allow(unsafe_code)]
unsafe impl Sync for FieldPtr {}
impl FieldPtr {
    pub(super) fn get(self) -> *mut C32 {
        self.0
    }
}

/// Scratch buffers of one thread: `a` holds an extended row or a block of columns, `b` is
/// rustfft's scratch.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) a: Vec<C32>,
    pub(super) b: Vec<C32>,
}

/// One [`Scratch`] per rayon thread, kept by the marcher so that steps allocate nothing.
pub(super) struct ScratchPool(Vec<Mutex<Scratch>>);

/// A thread's pooled scratch, or a fresh one if its slot is busy (never in practice).
pub(super) enum ScratchGuard<'a> {
    Pooled(MutexGuard<'a, Scratch>),
    Fresh(Scratch),
}

impl ScratchPool {
    pub(super) fn new() -> Self {
        ScratchPool(
            (0..rayon::current_num_threads().max(1))
                .map(|_| Mutex::new(Scratch::default()))
                .collect(),
        )
    }

    /// Scratch with `a.len() >= a_len` and `b.len() >= b_len` for the calling thread.
    pub(super) fn get(&self, a_len: usize, b_len: usize) -> ScratchGuard<'_> {
        let slot = rayon::current_thread_index().and_then(|i| self.0.get(i));
        let mut g = match slot.map(Mutex::try_lock) {
            Some(Ok(guard)) => ScratchGuard::Pooled(guard),
            _ => ScratchGuard::Fresh(Scratch::default()),
        };
        let s = g.scratch();
        if s.a.len() < a_len {
            s.a.resize(a_len, C32::default());
        }
        if s.b.len() < b_len {
            s.b.resize(b_len, C32::default());
        }
        g
    }
}

impl ScratchGuard<'_> {
    pub(super) fn scratch(&mut self) -> &mut Scratch {
        match self {
            ScratchGuard::Pooled(g) => g,
            ScratchGuard::Fresh(s) => s,
        }
    }
}
