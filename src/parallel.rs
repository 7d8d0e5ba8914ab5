//! Data parallelism where the target has threads.
//!
//! With the `parallel` feature this is rayon; without it (e.g. on
//! `wasm32-unknown-unknown`, which has no threads) the same calls run as
//! ordinary sequential iterators, so the stages are written once.

/// Frames of at least this many pixels are worked on by several threads
/// within the frame; smaller ones are done on one, where splitting the
/// work costs more than it saves.
pub(crate) const MIN_PARALLEL_PIXELS: usize = 2_000_000;

/// How many threads to split the work on one frame of `pixels` pixels
/// between: the pool's (rayon's current pool, so a caller's pool of one
/// thread keeps everything on it) for a large frame, else one. Results
/// never depend on it.
pub(crate) fn frame_threads(pixels: usize) -> usize {
    if pixels < MIN_PARALLEL_PIXELS {
        return 1;
    }
    #[cfg(feature = "parallel")]
    return rayon::current_num_threads();
    #[cfg(not(feature = "parallel"))]
    1
}

#[cfg(feature = "parallel")]
pub(crate) mod prelude {
    pub(crate) use rayon::prelude::*;
}

#[cfg(not(feature = "parallel"))]
pub(crate) mod prelude {
    /// Sequential stand-ins for rayon's slice methods.
    pub(crate) trait SequentialSlice<T> {
        fn par_iter(&self) -> std::slice::Iter<'_, T>;
        fn par_chunks_mut(&mut self, size: usize) -> std::slice::ChunksMut<'_, T>;
        fn par_chunks(&self, size: usize) -> std::slice::Chunks<'_, T>;
        fn par_iter_mut(&mut self) -> std::slice::IterMut<'_, T>;
    }

    impl<T> SequentialSlice<T> for [T] {
        fn par_iter(&self) -> std::slice::Iter<'_, T> {
            self.iter()
        }

        fn par_chunks_mut(&mut self, size: usize) -> std::slice::ChunksMut<'_, T> {
            self.chunks_mut(size)
        }

        fn par_chunks(&self, size: usize) -> std::slice::Chunks<'_, T> {
            self.chunks(size)
        }

        fn par_iter_mut(&mut self) -> std::slice::IterMut<'_, T> {
            self.iter_mut()
        }
    }

    /// Sequential stand-in for rayon's `into_par_iter`.
    pub(crate) trait SequentialIntoIter: IntoIterator + Sized {
        fn into_par_iter(self) -> Self::IntoIter {
            self.into_iter()
        }
    }

    impl<I: IntoIterator> SequentialIntoIter for I {}
}

/// Runs `work` on this thread and `aside` beside it, as a job another of
/// the pool's threads takes if one is free (else this thread runs it
/// after `work`); returns both results. Without threads, one after the
/// other.
pub(crate) fn beside<W, A, RW, RA>(work: W, aside: A) -> (RW, RA)
where
    W: FnOnce() -> RW + Send,
    A: FnOnce() -> RA + Send,
    RW: Send,
    RA: Send,
{
    #[cfg(feature = "parallel")]
    return rayon::join(work, aside);
    #[cfg(not(feature = "parallel"))]
    (work(), aside())
}

/// Items mapped on the pool's other threads while this thread goes on
/// producing them (see [`map_alongside`]).
#[cfg(feature = "parallel")]
pub(crate) struct Alongside<'a, 'scope, T, U> {
    scope: &'a rayon::Scope<'scope>,
    map: &'scope (dyn Fn(&T) -> U + Sync),
    size: usize,
    batch: Vec<T>,
    spawned: usize,
    settled: usize,
    sent: std::sync::mpsc::Sender<Mapped<T, U>>,
    done: std::sync::mpsc::Receiver<Mapped<T, U>>,
}

/// A batch's number and its items with what they map to (or the panic
/// that mapping them raised, raised again on the producing thread).
#[cfg(feature = "parallel")]
type Mapped<T, U> = (usize, std::thread::Result<Vec<(T, U)>>);

/// Runs `produce` on this thread with an [`Alongside`] it pushes items
/// to: each `batch` of them is mapped by `map` as a job of the pool, which
/// another thread takes while this one goes on. `produce` must
/// [`Alongside::settle`] what it pushed. Without threads the items are
/// mapped as they are settled. The results do not depend on the threads:
/// `map` sees one item at a time and they come back in their order.
#[cfg(feature = "parallel")]
pub(crate) fn map_alongside<'scope, T: Send + 'scope, U: Send + 'scope, R: Send>(
    batch: usize,
    map: &'scope (dyn Fn(&T) -> U + Sync),
    produce: impl for<'a> FnOnce(&mut Alongside<'a, 'scope, T, U>) -> R + Send,
) -> R {
    rayon::scope(|scope| {
        let (sent, done) = std::sync::mpsc::channel();
        let mut alongside = Alongside {
            scope,
            map,
            size: batch.max(1),
            batch: Vec::new(),
            spawned: 0,
            settled: 0,
            sent,
            done,
        };
        produce(&mut alongside)
    })
}

#[cfg(feature = "parallel")]
impl<'scope, T: Send + 'scope, U: Send + 'scope> Alongside<'_, 'scope, T, U> {
    /// Hands `item` on to be mapped.
    pub(crate) fn push(&mut self, item: T) {
        self.batch.push(item);
        if self.batch.len() >= self.size {
            let items = std::mem::take(&mut self.batch);
            let (number, sent, map) = (self.spawned, self.sent.clone(), self.map);
            self.spawned += 1;
            self.scope.spawn(move |_| {
                let mapped = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    items
                        .into_iter()
                        .map(|t| {
                            let u = map(&t);
                            (t, u)
                        })
                        .collect()
                }));
                // The receiver lives as long as the scope.
                let _ = sent.send((number, mapped));
            });
        }
    }

    /// Items pushed and not yet settled.
    pub(crate) fn unsettled(&self) -> usize {
        (self.spawned - self.settled) * self.size + self.batch.len()
    }

    /// Every item pushed since the last settling with what it maps to, in
    /// the order pushed. Maps the batch not yet full on this thread, then
    /// waits for the others, taking the pool's jobs meanwhile (the batches
    /// not yet taken by another thread among them).
    pub(crate) fn settle(&mut self) -> Vec<(T, U)> {
        let map = self.map;
        let last: Vec<(T, U)> = std::mem::take(&mut self.batch)
            .into_iter()
            .map(|t| {
                let u = map(&t);
                (t, u)
            })
            .collect();
        let mut batches: Vec<Option<Vec<(T, U)>>> =
            (self.settled..self.spawned).map(|_| None).collect();
        let mut waiting = batches.len();
        while waiting > 0 {
            match self.done.try_recv() {
                Ok((number, mapped)) => {
                    let items = mapped.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
                    batches[number - self.settled] = Some(items);
                    waiting -= 1;
                }
                Err(_) => {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::thread::yield_now();
                    }
                }
            }
        }
        self.settled = self.spawned;
        batches
            .into_iter()
            .flatten()
            .flatten()
            .chain(last)
            .collect()
    }
}

/// Items mapped as they are settled (see the threaded [`map_alongside`]).
#[cfg(not(feature = "parallel"))]
pub(crate) struct Alongside<'a, 'scope, T, U> {
    map: &'scope dyn Fn(&T) -> U,
    items: Vec<T>,
    _scope: std::marker::PhantomData<&'a ()>,
}

/// Runs `produce` with an [`Alongside`] that maps what it pushes when it
/// settles it.
#[cfg(not(feature = "parallel"))]
pub(crate) fn map_alongside<'scope, T: 'scope, U: 'scope, R>(
    _batch: usize,
    map: &'scope dyn Fn(&T) -> U,
    produce: impl for<'a> FnOnce(&mut Alongside<'a, 'scope, T, U>) -> R,
) -> R {
    produce(&mut Alongside {
        map,
        items: Vec::new(),
        _scope: std::marker::PhantomData,
    })
}

#[cfg(not(feature = "parallel"))]
impl<T, U> Alongside<'_, '_, T, U> {
    /// Hands `item` on to be mapped.
    pub(crate) fn push(&mut self, item: T) {
        self.items.push(item);
    }

    /// Items pushed and not yet settled.
    pub(crate) fn unsettled(&self) -> usize {
        self.items.len()
    }

    /// Every item pushed since the last settling with what it maps to, in
    /// the order pushed.
    pub(crate) fn settle(&mut self) -> Vec<(T, U)> {
        let map = self.map;
        std::mem::take(&mut self.items)
            .into_iter()
            .map(|t| {
                let u = map(&t);
                (t, u)
            })
            .collect()
    }
}

#[cfg(all(test, feature = "parallel"))]
mod tests {
    use super::*;

    /// What `produce` pushes comes back mapped, in its order, across
    /// settlings, whether the batches are mapped by another thread or
    /// not.
    #[test]
    fn items_come_back_mapped_in_their_order() {
        let square = |x: &u64| x * x;
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (settlings, unsettled) = pool.install(|| {
                map_alongside(4, &square, |along| {
                    let mut settlings = Vec::new();
                    let mut unsettled = Vec::new();
                    for x in 0..23u64 {
                        along.push(x);
                        unsettled.push(along.unsettled());
                        if x == 9 || x == 10 {
                            settlings.push(along.settle());
                        }
                    }
                    settlings.push(along.settle());
                    settlings.push(along.settle());
                    (settlings, unsettled)
                })
            });
            let expected: Vec<Vec<(u64, u64)>> = [0..10, 10..11, 11..23, 0..0]
                .map(|r| r.map(|x| (x, x * x)).collect())
                .to_vec();
            assert_eq!(settlings, expected, "{threads} threads");
            let counts: Vec<usize> = (0..23)
                .map(|x| {
                    if x < 10 {
                        x + 1
                    } else if x == 10 {
                        1
                    } else {
                        x - 10
                    }
                })
                .collect();
            assert_eq!(unsettled, counts);
        }
    }

    /// A panic while mapping on another thread is raised where the items
    /// are settled.
    #[test]
    #[should_panic(expected = "seven")]
    fn a_panic_in_a_batch_reaches_the_producer() {
        let refuse = |x: &u64| if *x == 7 { panic!("seven") } else { *x };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            map_alongside(2, &refuse, |along| {
                (0..12u64).for_each(|x| along.push(x));
                along.settle()
            })
        });
    }
}
