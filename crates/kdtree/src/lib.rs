//! raybench-kdtree (in progress).
