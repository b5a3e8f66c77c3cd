//! Speed labels on a locus (a polar plot's 1X vector against speed) that
//! never overlap each other or the marks they must not hide: the first and
//! last points are always labelled, then points spread along the locus are
//! tried in turn, each at a few offsets around its point, and kept only
//! where the label's box is clear.
//!
//! Everything here is in pixels (x right, y down), with text boxes estimated
//! from the font size (DejaVu Sans averages about 0.6 em per character).

/// An axis-aligned box [px]: left, top, width, height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextBox {
    /// Left edge [px].
    pub x: f64,
    /// Top edge [px].
    pub y: f64,
    /// Width [px].
    pub w: f64,
    /// Height [px].
    pub h: f64,
}

impl TextBox {
    /// True when the two boxes share any area (touching edges do not).
    pub fn overlaps(&self, o: &TextBox) -> bool {
        self.x < o.x + o.w && o.x < self.x + self.w && self.y < o.y + o.h && o.y < self.y + self.h
    }

    /// True when the box lies inside `bounds`.
    pub fn inside(&self, bounds: &TextBox) -> bool {
        self.x >= bounds.x
            && self.y >= bounds.y
            && self.x + self.w <= bounds.x + bounds.w
            && self.y + self.h <= bounds.y + bounds.h
    }
}

/// Estimated box of `text` at `font_px` with its top-left corner at (x, y).
pub fn text_box(text: &str, font_px: f64, x: f64, y: f64) -> TextBox {
    TextBox {
        x,
        y,
        w: 0.62 * font_px * text.chars().count() as f64 + 2.0,
        h: 1.2 * font_px,
    }
}

/// A placed label: index of its point and its box's top-left corner [px].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// Index into the points.
    pub index: usize,
    /// Left edge of the text [px].
    pub x: f64,
    /// Top edge of the text [px].
    pub y: f64,
}

/// Chooses labels for `points` [px] with texts `texts` at `font_px`: at most
/// `max` labels, the first and last point first, none overlapping another,
/// any box in `avoid` or a circle of radius `mark_px` around any labelled
/// point, and all inside `bounds`. Returns the placed labels by point index.
pub fn place(
    points: &[(f64, f64)],
    texts: &[String],
    font_px: f64,
    mark_px: f64,
    max: usize,
    avoid: &[TextBox],
    bounds: TextBox,
) -> Vec<Placed> {
    let n = points.len().min(texts.len());
    if n == 0 || max == 0 {
        return Vec::new();
    }
    // Candidates: first, last, then points at evenly spread arc length,
    // refined by halving (1/2, 1/4, 3/4, ...), so labels spread out.
    let mut arc = vec![0.0; n];
    for i in 1..n {
        let (a, b) = (points[i - 1], points[i]);
        arc[i] = arc[i - 1] + (b.0 - a.0).hypot(b.1 - a.1);
    }
    let total = arc[n - 1];
    let mut order: Vec<usize> = vec![0, n - 1];
    let mut denominator = 2usize;
    while denominator <= 64 && order.len() < n {
        for k in (1..denominator).step_by(2) {
            let target = total * k as f64 / denominator as f64;
            let i = arc.partition_point(|&s| s < target).min(n - 1);
            if !order.contains(&i) {
                order.push(i);
            }
        }
        denominator *= 2;
    }
    let mut taken: Vec<TextBox> = avoid.to_vec();
    let mut placed: Vec<Placed> = Vec::new();
    let marks: Vec<TextBox> = order
        .iter()
        .take(2)
        .map(|&i| TextBox {
            x: points[i].0 - mark_px,
            y: points[i].1 - mark_px,
            w: 2.0 * mark_px,
            h: 2.0 * mark_px,
        })
        .collect();
    taken.extend(marks);
    for &i in &order {
        if placed.len() >= max {
            break;
        }
        let (px, py) = points[i];
        let probe = text_box(&texts[i], font_px, 0.0, 0.0);
        let gap = mark_px + 2.0;
        let offsets = [
            (gap, -probe.h / 2.0),
            (-probe.w - gap, -probe.h / 2.0),
            (-probe.w / 2.0, -probe.h - gap),
            (-probe.w / 2.0, gap),
            (gap, -probe.h - gap / 2.0),
            (gap, gap / 2.0),
            (-probe.w - gap, -probe.h - gap / 2.0),
            (-probe.w - gap, gap / 2.0),
        ];
        for (dx, dy) in offsets {
            let b = text_box(&texts[i], font_px, px + dx, py + dy);
            if b.inside(&bounds) && !taken.iter().any(|t| t.overlaps(&b)) {
                taken.push(b);
                placed.push(Placed {
                    index: i,
                    x: b.x,
                    y: b.y,
                });
                break;
            }
        }
    }
    placed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_never_overlap_and_keep_start_and_end() {
        // A spiral crowding towards its centre (a locus starting at slow
        // roll near the origin), 300 points.
        let pts: Vec<(f64, f64)> = (0..300)
            .map(|i| {
                let t = i as f64 / 299.0;
                let r = 5.0 + 250.0 * t * t;
                let a = 6.0 * t;
                (350.0 + r * a.cos(), 350.0 + r * a.sin())
            })
            .collect();
        let texts: Vec<String> = (0..300)
            .map(|i| format!("{:.1} Hz", 10.0 + i as f64 * 0.3))
            .collect();
        let bounds = TextBox {
            x: 0.0,
            y: 0.0,
            w: 700.0,
            h: 700.0,
        };
        let placed = place(&pts, &texts, 11.0, 5.0, 14, &[], bounds);
        assert!(placed.len() >= 8, "{}", placed.len());
        assert_eq!(placed[0].index, 0);
        assert_eq!(placed[1].index, 299);
        let boxes: Vec<TextBox> = placed
            .iter()
            .map(|p| text_box(&texts[p.index], 11.0, p.x, p.y))
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.inside(&bounds));
            for b in &boxes[i + 1..] {
                assert!(!a.overlaps(b), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn labels_at_the_same_place_give_one() {
        // Every point at the same pixel (e.g. 92 and 100 Hz on one spot).
        let pts = vec![(100.0, 100.0); 10];
        let texts: Vec<String> = (0..10).map(|i| format!("{} Hz", 90 + i)).collect();
        let bounds = TextBox {
            x: 0.0,
            y: 0.0,
            w: 400.0,
            h: 400.0,
        };
        let placed = place(&pts, &texts, 11.0, 4.0, 10, &[], bounds);
        // Eight offsets around one point at most, never overlapping.
        assert!(placed.len() <= 8 && placed.len() >= 2);
        let boxes: Vec<TextBox> = placed
            .iter()
            .map(|p| text_box(&texts[p.index], 11.0, p.x, p.y))
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                assert!(!a.overlaps(b));
            }
        }
    }
}
