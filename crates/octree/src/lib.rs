//! raybench-octree (in progress).
