//! Data parallelism where the target has threads.
//!
//! With the `parallel` feature this is rayon; without it (e.g. on
//! `wasm32-unknown-unknown`, which has no threads) the same calls run as
//! ordinary sequential iterators, so the stages are written once.

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
    }

    impl<T> SequentialSlice<T> for [T] {
        fn par_iter(&self) -> std::slice::Iter<'_, T> {
            self.iter()
        }

        fn par_chunks_mut(&mut self, size: usize) -> std::slice::ChunksMut<'_, T> {
            self.chunks_mut(size)
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
