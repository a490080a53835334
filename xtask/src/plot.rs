//! The plot backend: renders a pipeline's `scenarios::Chart` (labelled series drawn as lines
//! or markers on one pair of axes) to SVG with plotters.

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use scenarios::{Chart, Style};

/// Matplotlib's "tab10" colours: distinct on white and for most colour-blind readers.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    (lo - pad, hi + pad)
}

/// Draws the chart into an SVG document of 760×520 pixels.
pub fn render(chart: &Chart) -> Result<String> {
    let (axes, series) = (&chart.axes, &chart.series);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 520)).into_drawing_area();
        let to_err = |e: &dyn std::fmt::Display| anyhow!("plot {:?}: {e}", axes.title);
        root.fill(&WHITE).map_err(|e| to_err(&e))?;
        let (x0, x1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
        let (y0, y1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
        let mut chart = ChartBuilder::on(&root)
            .caption(&axes.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| to_err(&e))?;
        chart
            .configure_mesh()
            .x_desc(&axes.x)
            .y_desc(&axes.y)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|e| to_err(&e))?;
        for s in series {
            let colour = PALETTE[s.colour % PALETTE.len()].to_rgba();
            let drawn = match s.style {
                Style::Line => chart.draw_series(LineSeries::new(
                    s.points.iter().copied(),
                    colour.stroke_width(2),
                )),
                Style::ThinLine => chart.draw_series(LineSeries::new(
                    s.points.iter().copied(),
                    colour.mix(0.6).stroke_width(1),
                )),
                Style::Markers => chart.draw_series(
                    s.points
                        .iter()
                        .map(|&p| Circle::new(p, 2, colour.mix(0.7).filled())),
                ),
            }
            .map_err(|e| to_err(&e))?;
            if !s.label.is_empty() {
                drawn.label(s.label.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|e| to_err(&e))?;
        root.present().map_err(|e| to_err(&e))?;
    }
    Ok(svg)
}
