//! The spatial-median k-d tree: the textbook baseline (Bentley 1975's k-d tree applied to ray
//! tracing; Kaplan 1985). Each cell is cut in its middle, the axes taken in turn by depth
//! (x, y, z, x, …; an axis on which the cell is flat is skipped), until a cell holds at most
//! `leaf_size` triangles or the depth limit is reached. Triangles are classified with the same
//! rule as the SAH builder and straddlers re-clipped to each half, so the references are
//! exactly as tight; only the choice of plane ignores where the triangles are. O(N) per level,
//! O(N log N) in all. Cheap to build and oblivious to the scene: it spends nodes on empty space
//! and splits dense clusters no more finely than sparse regions. One guard beyond the textbook:
//! a cell whose every triangle would land in both halves is not split (the split would separate
//! nothing and only duplicate references, exponentially in the remaining depth).

use super::{Ctx, Out, Share, Stop};
use crate::clip::{Side, halves, side, straddler_bounds};
use raybench_geom::Aabb;

pub(crate) fn build(ctx: &Ctx, ids: &[u32], root: &Aabb, share: Share, out: &mut Out) {
    let items = ids
        .iter()
        .map(|&i| (i, ctx.tris[i as usize].bounds()))
        .collect();
    node(ctx, items, *root, 0, share, out);
}

/// Triangle id and its bounds clipped to the current cell.
type Item = (u32, Aabb);

fn node(ctx: &Ctx, items: Vec<Item>, cell: Aabb, depth: u32, share: Share, out: &mut Out) {
    let n = items.len();
    let leaf = |out: &mut Out, items: Vec<Item>, stop: Stop| {
        out.leaf(
            ctx,
            &cell,
            depth,
            items.into_iter().map(|x| x.0).collect(),
            stop,
        );
    };
    if n <= ctx.params.leaf_size as usize {
        return leaf(out, items, Stop::Cost);
    }
    if depth >= ctx.max_depth {
        return leaf(out, items, Stop::Depth);
    }
    let plane = (0..3).map(|i| (depth as usize + i) % 3).find_map(|a| {
        let p = cell.min[a] * 0.5 + cell.max[a] * 0.5;
        (cell.min[a] < p && p < cell.max[a]).then_some((a, p))
    });
    let Some((axis, p)) = plane else {
        return leaf(out, items, Stop::Cost);
    };
    let (cb, ca) = halves(&cell, axis, p);
    let (mut below, mut above) = (Vec::new(), Vec::new());
    for &(i, b) in &items {
        match side(&b, axis, p) {
            Side::Below | Side::InPlane => below.push((i, b)),
            Side::Above => above.push((i, b)),
            Side::Both => {
                let t = &ctx.tris[i as usize];
                below.push((i, straddler_bounds(t, &cb)));
                above.push((i, straddler_bounds(t, &ca)));
            }
        }
    }
    if below.len() == n && above.len() == n {
        return leaf(out, items, Stop::Cost);
    }
    if !share.fits(below.len(), above.len()) {
        return leaf(out, items, Stop::Memory);
    }
    drop(items);
    let (nb, na) = (below.len(), above.len());
    let at = out.open_interior(ctx, &cell);
    let above_at = if depth < Share::PROPORTIONAL_DEPTH {
        let (share_b, share_a) = share.proportional(nb, na);
        if ctx.fork(n, depth) {
            let ((), sub) = rayon::join(
                || node(ctx, below, cb, depth + 1, share_b, out),
                || {
                    let mut sub = Out::default();
                    node(ctx, above, ca, depth + 1, share_a, &mut sub);
                    sub
                },
            );
            let above_at = out.nodes.len();
            out.append(sub);
            above_at
        } else {
            node(ctx, below, cb, depth + 1, share_b, out);
            let above_at = out.nodes.len();
            node(ctx, above, ca, depth + 1, share_a, out);
            above_at
        }
    } else {
        let before = out.shape.refs;
        node(ctx, below, cb, depth + 1, Share(share.0 - na as u64), out);
        let used = out.shape.refs - before;
        let above_at = out.nodes.len();
        node(ctx, above, ca, depth + 1, Share(share.0 - used), out);
        above_at
    };
    out.close_interior(at, axis, p, above_at);
}
