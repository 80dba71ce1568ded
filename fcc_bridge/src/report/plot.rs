//! PNG line/scatter plots (plotters, bitmap backend).

use plotters::prelude::*;

pub struct Line<'a> {
    pub name: &'a str,
    pub pts: Vec<(f64, f64)>,
    pub color: RGBColor,
    /// Draw points instead of a line.
    pub dots: bool,
}

fn bounds(lines: &[Line]) -> ((f64, f64), (f64, f64)) {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = x;
    for l in lines {
        for &(a, b) in &l.pts {
            if a.is_finite() && b.is_finite() {
                x = (x.0.min(a), x.1.max(a));
                y = (y.0.min(b), y.1.max(b));
            }
        }
    }
    if !x.0.is_finite() {
        return ((0.0, 1.0), (0.0, 1.0));
    }
    let pad = |r: (f64, f64)| {
        let d = ((r.1 - r.0) * 0.05).max(1e-3);
        (r.0 - d, r.1 + d)
    };
    (pad(x), pad(y))
}

/// One chart; `equal` makes both axes the same scale (paths).
pub fn chart(
    path: &std::path::Path,
    title: &str,
    xl: &str,
    yl: &str,
    lines: Vec<Line>,
    equal: bool,
) -> Result<(), String> {
    let root = BitMapBackend::new(path, (1000, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    draw(&root, title, xl, yl, lines, equal)?;
    root.present().map_err(|e| e.to_string())
}

/// Several charts stacked vertically in one PNG (one `(title, y label, lines)` per panel,
/// sharing the x label).
pub fn panels(
    path: &std::path::Path,
    xl: &str,
    panels: Vec<(String, &str, Vec<Line>)>,
) -> Result<(), String> {
    let n = panels.len().max(1);
    let root = BitMapBackend::new(path, (1000, 420 * n as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    for (area, (title, yl, lines)) in root.split_evenly((n, 1)).iter().zip(panels) {
        draw(area, &title, xl, yl, lines, false)?;
    }
    root.present().map_err(|e| e.to_string())
}

fn draw(
    root: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    title: &str,
    xl: &str,
    yl: &str,
    lines: Vec<Line>,
    equal: bool,
) -> Result<(), String> {
    let ((mut x0, mut x1), (mut y0, mut y1)) = bounds(&lines);
    if equal {
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let h = ((x1 - x0) / 2.0).max((y1 - y0) / 2.0);
        (x0, x1, y0, y1) = (cx - h, cx + h, cy - h, cy + h);
    }
    let mut c = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    c.configure_mesh()
        .x_desc(xl)
        .y_desc(yl)
        .draw()
        .map_err(|e| e.to_string())?;
    for l in lines {
        let col = l.color;
        let pts = l
            .pts
            .into_iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let s = if l.dots {
            c.draw_series(pts.map(|p| Circle::new(p, 1, col.filled())))
                .map_err(|e| e.to_string())?
        } else {
            c.draw_series(LineSeries::new(pts, col))
                .map_err(|e| e.to_string())?
        };
        // Unnamed lines (guides, repeated segments) get no legend entry.
        if !l.name.is_empty() {
            if l.dots {
                s.label(l.name)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 3, col.filled()));
            } else {
                s.label(l.name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
            }
        }
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())
}
