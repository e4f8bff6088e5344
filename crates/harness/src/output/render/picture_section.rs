//! The page's pictures of the primary view, one scene at a time: the colour scale with its
//! numbers, the render once, a heatmap per counting structure, a mask per disagreeing one.
//! Every picture is shown about 420 pixels wide and links to its file at full size.

use super::ScenePictures;
use super::page::escape;
use super::pictures::{log_position, viridis};
use super::ticks::thousands;
use std::fmt::Write as _;

/// Display width of a picture on the page (pixels); the link opens the file at full size.
const SHOWN: u32 = 420;

/// Every scene's pictures under one heading (the index page).
pub(crate) fn pictures_section(s: &mut String, pictures: &[ScenePictures]) {
    if pictures.is_empty() {
        return;
    }
    s.push_str("<h2 id=\"pictures\">Primary rays, per pixel</h2>\n");
    explanation(s);
    for p in pictures {
        scene_pictures(s, p);
    }
}

/// What the pictures show, once above them.
pub(crate) fn explanation(s: &mut String) {
    s.push_str(
        "<p class=\"note\">Traversal cost is interior nodes + leaves + triangle tests + cells \
         per pixel, on one logarithmic colour scale per scene, so structures can be compared by \
         eye. The render shades the reference's closest hits. A mask shows where a structure's \
         answer differs from the reference's: amber for an explained difference (tie, boundary, \
         edge-ambiguous), red for a mismatch, each ringed by a paler halo so that a single pixel \
         can be found; structures that differ at the same pixels share one mask. Click a \
         picture for the full-size file.</p>\n",
    );
}

/// The pictures of one scene.
pub(crate) fn scene_pictures(s: &mut String, p: &ScenePictures) {
    let _ = writeln!(s, "<h3>{}</h3>", escape(&p.scene));
    let size = format!("{}×{} pixels", p.width, p.height);
    match &p.fallback {
        None => {
            let _ = writeln!(s, "<p class=\"note\">{size}.</p>");
        }
        Some(why) => {
            let _ = writeln!(
                s,
                "<p class=\"note\"><b>Small pictures:</b> drawn from the planes stored in \
                 report.json ({size}, each pixel the mean cost of a block of traced pixels), \
                 because {}.</p>",
                escape(why)
            );
        }
    }
    let class = if p.fallback.is_some() {
        "picture-small"
    } else {
        "picture"
    };
    let counted: Vec<_> = p
        .structures
        .iter()
        .filter_map(|st| st.heatmap.as_ref().map(|f| (&st.structure, f)))
        .collect();
    if !counted.is_empty() {
        colour_bar(
            s,
            p.max_cost,
            &format!("viridis-{}", super::names::slug(&p.scene)),
        );
    }
    s.push_str("<div style=\"display:flex;flex-wrap:wrap;gap:12px\">\n");
    if let Some((reference, file)) = &p.render {
        figure(
            s,
            class,
            file,
            &format!("render: {reference}'s closest hits"),
        );
    }
    for (structure, file) in &counted {
        figure(s, class, file, &format!("{structure}: traversal cost"));
    }
    s.push_str("</div>\n");
    let uncounted = names(p, |st| st.heatmap.is_none());
    if !uncounted.is_empty() {
        let _ = writeln!(
            s,
            "<p class=\"note\">Not counted (no work counters): {}.</p>",
            escape(&uncounted)
        );
    }
    // One figure per mask file: structures that disagree at the same pixels share one.
    let mut masks: Vec<(&str, Vec<&str>, u64, u64)> = Vec::new();
    for st in &p.structures {
        let Some(file) = st.mask.as_deref() else {
            continue;
        };
        match masks.iter_mut().find(|m| m.0 == file) {
            Some(m) => m.1.push(&st.structure),
            None => masks.push((
                file,
                vec![&st.structure],
                st.explained_pixels,
                st.mismatch_pixels,
            )),
        }
    }
    if !masks.is_empty() {
        s.push_str("<div style=\"display:flex;flex-wrap:wrap;gap:12px\">\n");
        for (file, structures, explained, mismatched) in masks {
            let caption = format!(
                "{}: {} differ{} for an explained reason, {}",
                structures.join(", "),
                count(explained, "pixel"),
                if explained == 1 { "s" } else { "" },
                count(mismatched, "mismatch")
            );
            figure(s, class, file, &caption);
        }
        s.push_str("</div>\n");
    }
    let reference = p.render.as_ref().map_or("the reference", |r| r.0.as_str());
    let agreeing = names(p, |st| st.mask.is_none() && st.structure != reference);
    if !agreeing.is_empty() {
        let _ = writeln!(
            s,
            "<p class=\"note\">The same answer as {} at every pixel (no mask): {}.</p>",
            escape(reference),
            escape(&agreeing)
        );
    }
}

fn names(
    p: &ScenePictures,
    keep: impl Fn(&crate::pipeline::picture::StructurePicture) -> bool,
) -> String {
    let kept: Vec<&str> = p
        .structures
        .iter()
        .filter(|st| keep(st))
        .map(|st| st.structure.as_str())
        .collect();
    kept.join(", ")
}

/// `1 pixel`, `2 pixels`, `0 mismatches`.
fn count(n: u64, noun: &str) -> String {
    let plural = if noun.ends_with('h') { "es" } else { "s" };
    format!(
        "{} {noun}{}",
        thousands(n),
        if n == 1 { "" } else { plural }
    )
}

/// One picture at display size, linked to its file, captioned and titled.
fn figure(s: &mut String, class: &str, file: &str, caption: &str) {
    let (file, caption) = (escape(file), escape(caption));
    // Small pictures are enlarged with visible pixels rather than blurred.
    let pixelated = if class == "picture" {
        ""
    } else {
        "image-rendering:pixelated;"
    };
    let _ = writeln!(
        s,
        "<figure style=\"margin:0\"><a href=\"{file}\"><img class=\"{class}\" src=\"{file}\" \
         alt=\"{caption}\" title=\"{caption}\" width=\"{SHOWN}\" style=\"width:{SHOWN}px;\
         max-width:100%;height:auto;{pixelated}border:1px solid #ddd\"></a>\
         <figcaption>{caption}</figcaption></figure>"
    );
}

/// Bar geometry: left margin, bar width and height, in SVG units.
const BAR_X: f64 = 12.0;
const BAR_W: f64 = 400.0;
const BAR_H: f64 = 14.0;

/// The scene's colour scale as an inline SVG: the viridis gradient on the log scale, with
/// ticks at 0, 1, 10, 100, … and the maximum, each labelled with its number.
fn colour_bar(s: &mut String, max: u64, id: &str) {
    let _ = write!(
        s,
        "<p class=\"note\">Traversal cost per pixel (logarithmic):</p>\n<svg \
         xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"40\" role=\"img\" \
         aria-label=\"colour scale from 0 to {max}\"><defs><linearGradient id=\"{id}\">",
        w = BAR_W + 2.0 * BAR_X + 30.0
    );
    for i in 0..=16 {
        let [r, g, b] = viridis(f64::from(i) / 16.0);
        let _ = write!(
            s,
            "<stop offset=\"{}%\" stop-color=\"rgb({r},{g},{b})\"/>",
            i * 100 / 16
        );
    }
    let _ = write!(
        s,
        "</linearGradient></defs><rect x=\"{BAR_X}\" y=\"0\" width=\"{BAR_W}\" height=\"{BAR_H}\" \
         fill=\"url(#{id})\"/>"
    );
    for (value, x) in ticks(max) {
        let _ = write!(
            s,
            "<line x1=\"{x:.1}\" x2=\"{x:.1}\" y1=\"{BAR_H}\" y2=\"{}\" stroke=\"#444\"/>\
             <text x=\"{x:.1}\" y=\"34\" font-size=\"11\" text-anchor=\"middle\" \
             font-family=\"sans-serif\">{}</text>",
            BAR_H + 5.0,
            thousands(value)
        );
    }
    s.push_str("</svg>\n");
}

/// The labelled values and their x positions: 0, the powers of ten below `max`, and `max`; a
/// label too close to the one before it (or to the maximum's) is left out.
fn ticks(max: u64) -> Vec<(u64, f64)> {
    let max = max.max(1);
    let x = |v: u64| BAR_X + BAR_W * log_position(v, max);
    let half_width = |v: u64| 3.5 * thousands(v).len() as f64 + 2.0;
    let mut values = vec![0];
    let mut p = 1u64;
    while p < max {
        values.push(p);
        p = p.saturating_mul(10);
    }
    let mut out: Vec<(u64, f64)> = Vec::new();
    for v in values {
        let clear_of_last = out
            .last()
            .is_none_or(|&(u, xu)| x(v) - xu >= half_width(u) + half_width(v));
        let clear_of_max = x(max) - x(v) >= half_width(max) + half_width(v);
        if clear_of_last && clear_of_max {
            out.push((v, x(v)));
        }
    }
    out.push((max, x(max)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_decades_below_the_maximum_and_the_maximum() {
        let values: Vec<u64> = ticks(23_817).iter().map(|t| t.0).collect();
        assert_eq!(values, [0, 1, 10, 100, 1000, 23_817]);
        // 10,000 sits too close to 23,817 to be labelled beside it.
        let xs: Vec<f64> = ticks(23_817).iter().map(|t| t.1).collect();
        assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        assert_eq!(*xs.last().unwrap(), BAR_X + BAR_W);
        assert_eq!(ticks(0).iter().map(|t| t.0).collect::<Vec<_>>(), [0, 1]);
        assert_eq!(ticks(u64::MAX).last().unwrap().0, u64::MAX);
    }
}
