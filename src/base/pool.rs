//! Scratch shared by the tasks of a parallel loop: as many items as threads run the loop at
//! once, not one per work unit.
//!
//! The loops split their work into a fixed set of units (so that results never depend on the
//! thread count), and every unit overwrites whatever scratch it gets before reading it, so
//! which item a unit gets changes no value. A task takes an item for the length of one unit and
//! gives it back; the pool starts with one item per rayon thread and only grows (once) if the
//! loop runs on a pool with more threads than the one it was made on.

use std::sync::Mutex;

/// A pool of scratch items of type `T`, and how to make one.
pub struct Pool<T> {
    items: Mutex<Vec<T>>,
    make: Box<dyn Fn() -> T + Send + Sync>,
}

impl<T> Pool<T> {
    /// One item per thread of the current rayon pool, each made by `make` (as are the items
    /// made later, if more tasks run at once than there are items).
    pub fn per_thread(make: impl Fn() -> T + Send + Sync + 'static) -> Self {
        let n = rayon::current_num_threads().max(1);
        Pool {
            items: Mutex::new(std::iter::repeat_with(&make).take(n).collect()),
            make: Box::new(make),
        }
    }

    /// Run `f` with an item of the pool.
    pub fn with<R>(&self, f: impl FnOnce(&mut T) -> R) -> R {
        let taken = self.lock().pop();
        let mut item = taken.unwrap_or_else(|| (self.make)());
        let r = f(&mut item);
        self.lock().push(item);
        r
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<T>> {
        // A panic in a task leaves the items whole (they are scratch), so a poisoned lock is
        // still usable.
        self.items.lock().unwrap_or_else(|e| e.into_inner())
    }
}
