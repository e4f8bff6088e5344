//! raybench-grid (in progress).
