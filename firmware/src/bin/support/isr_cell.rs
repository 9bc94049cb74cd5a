//! `IsrCell`: a static shared by interrupt handlers of one priority level, without a lock.
//!
//! The firmware object is used by two handlers (the tick and the edge's bookkeeping). Both run at the
//! same NVIC priority, which the binaries set explicitly, so neither can preempt the other, and the
//! main thread touches the object only before it enables them (or with both masked). Under those two
//! rules a `&mut` from inside a handler is unique. The edge interrupt itself runs at a higher
//! priority and never touches the object (atomics and registers only), so its stop write waits for
//! no critical section and no tick.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

/// Storage for a `T` initialised once at start-up and then used only from same-priority handlers.
pub struct IsrCell<T>(UnsafeCell<MaybeUninit<T>>);

// SAFETY: access is serialised by the priority rule documented on `get`.
unsafe impl<T> Sync for IsrCell<T> {}

impl<T> IsrCell<T> {
    /// Empty storage.
    pub const fn new() -> Self {
        IsrCell(UnsafeCell::new(MaybeUninit::uninit()))
    }

    /// Store the value.
    ///
    /// # Safety
    /// Call exactly once, before any handler that calls [`IsrCell::get`] is enabled.
    pub unsafe fn init(&self, value: T) {
        // SAFETY: no handler can observe the cell yet (caller's contract).
        unsafe { (*self.0.get()).write(value) };
    }

    /// The value, mutably.
    ///
    /// # Safety
    /// Only after [`IsrCell::init`], and only from handlers that share one priority level (or from the
    /// main thread with those handlers masked), so that two `&mut` never coexist.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn get(&self) -> &mut T {
        // SAFETY: initialised and unaliased (caller's contract).
        unsafe { (*self.0.get()).assume_init_mut() }
    }
}
