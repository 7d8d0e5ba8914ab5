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
