//! Scratch shared by the tasks of a parallel loop: as many items as threads run the loop at
//! once, not one per work unit.
//!
//! The loops split their work into a fixed set of units (so that results never depend on the
//! thread count), and every unit overwrites whatever scratch it gets before reading it, so
//! which item a unit gets changes no value. A task takes an item for the length of one unit and
//! gives it back; the pool starts with one item per rayon thread and only grows (once) if the
//! loop runs on a pool with more threads than the one it was made on.

use std::sync::Mutex;

/// A pool of scratch items of type `T`.
pub struct Pool<T> {
    items: Mutex<Vec<T>>,
}

impl<T> Pool<T> {
    /// One item per thread of the current rayon pool, each made by `make`.
    pub fn per_thread(make: impl FnMut() -> T) -> Self {
        let n = rayon::current_num_threads().max(1);
        Pool {
            items: Mutex::new(std::iter::repeat_with(make).take(n).collect()),
        }
    }

    /// Run `f` with an item of the pool (made by `make` if every item is in use).
    pub fn with<R>(&self, make: impl FnOnce() -> T, f: impl FnOnce(&mut T) -> R) -> R {
        let taken = self.lock().pop();
        let mut item = taken.unwrap_or_else(make);
        let r = f(&mut item);
        self.lock().push(item);
        r
    }

    /// Number of items the pool holds now (those in use are not counted).
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// Whether the pool holds no item now.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<T>> {
        // A panic in a task leaves the items whole (they are scratch), so a poisoned lock is
        // still usable.
        self.items.lock().unwrap_or_else(|e| e.into_inner())
    }
}
