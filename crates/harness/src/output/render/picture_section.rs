//! The page's section of per-pixel pictures of the primary workload: per scene, the colour
//! scale and one row of pictures per structure.

use super::ScenePictures;
use super::page::escape;
use std::fmt::Write as _;

pub(crate) fn pictures_section(s: &mut String, pictures: &[ScenePictures]) {
    if pictures.is_empty() {
        return;
    }
    s.push_str(
        "<h2>Primary rays, per pixel</h2>\n<p class=\"note\">Traversal cost is interior nodes + \
         leaves + triangle tests + cells per pixel, on one logarithmic colour scale per scene (legend below each \
         scene). The mask shows where the structure disagrees with the reference: amber for an \
         explained difference (tie, boundary, edge-ambiguous), red for a mismatch.</p>\n",
    );
    for p in pictures {
        let _ = writeln!(
            s,
            "<h3>{}</h3>\n<p class=\"note\">cost scale (logarithmic): 0 <img src=\"images/legend-viridis.png\" \
             alt=\"colour scale\" style=\"vertical-align:middle;width:256px;height:14px\"> {} \
             (downsampled {}×{} pixels per stored pixel)</p>",
            escape(&p.scene),
            p.max_cost,
            p.downsample,
            p.downsample
        );
        s.push_str("<table><tr><th class=\"l\">structure</th><th>traversal cost</th><th>render</th><th>disagrees with the reference</th></tr>\n");
        for (st, heat, render, mask) in &p.rows {
            let heat = heat.as_ref().map_or("not counted".to_string(), |f| {
                format!("<img class=\"px\" src=\"{}\" alt=\"cost\">", escape(f))
            });
            let _ = writeln!(
                s,
                "<tr><td class=\"l\">{}</td><td>{heat}</td><td><img class=\"px\" src=\"{}\" alt=\"render\"></td>\
                 <td><img class=\"px\" src=\"{}\" alt=\"mask\"></td></tr>",
                escape(st),
                escape(render),
                escape(mask)
            );
        }
        s.push_str("</table>\n");
    }
}
