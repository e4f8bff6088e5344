//! Shape and SAH cost of a wide tree, for the report.

use super::BvhWide;
use raybench_accel::{BuildStats, SAH_INTERSECTION_COST, SAH_TRAVERSAL_COST};

impl<const W: usize> BvhWide<W> {
    /// Shape and SAH cost of the wide tree (a wide node costs one traversal step: one SIMD
    /// node test), with the constants shared by every structure.
    pub(super) fn measure(&self) -> BuildStats {
        let mut s = BuildStats::default();
        if self.tri4s.is_empty() {
            return s;
        }
        let root_area = self.root_bounds.surface_area();
        let mut sah = 0.0;
        let mut children = 0u64;
        let mut stack = vec![(self.root, self.root_bounds, 0u32)];
        while let Some((r, b, depth)) = stack.pop() {
            s.max_depth = s.max_depth.max(depth);
            let area = if root_area > 0.0 {
                b.surface_area() / root_area
            } else {
                0.0
            };
            if r.is_leaf() {
                s.leaves += 1;
                s.refs += r.count as u64;
                sah += area * SAH_INTERSECTION_COST * r.count as f64;
            } else {
                s.nodes += 1;
                sah += area * SAH_TRAVERSAL_COST;
                let n = &self.nodes[r.index as usize];
                children += n.children() as u64;
                for i in 0..n.children() {
                    stack.push((n.child[i], n.child_bounds(i), depth + 1));
                }
            }
        }
        s.extra.insert(
            "mean_children".into(),
            children as f64 / s.nodes.max(1) as f64,
        );
        s.extra.insert(
            "mean_leaf_size".into(),
            s.refs as f64 / s.leaves.max(1) as f64,
        );
        s.extra.insert(
            "lane_fill".into(),
            s.refs as f64 / (4 * self.tri4s.len()).max(1) as f64,
        );
        s.extra
            .insert("avx2_kernels".into(), self.uses_avx2() as u8 as f64);
        s.extra.insert(
            "avx512_registers".into(),
            self.avx512_registers() as u8 as f64,
        );
        if let Some(r) = &self.reinsertion {
            r.insert_into(&mut s.extra);
        }
        s.nodes += s.leaves;
        s.sah_cost = (root_area > 0.0).then_some(sah);
        s
    }
}
