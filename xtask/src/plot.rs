//! The plot backend: renders a pipeline's `scenarios::Chart` (labelled series drawn as lines,
//! markers or bars on one pair of axes) to SVG with plotters.

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use scenarios::{BAR_WIDTH, Chart, Series, Style, YAxis};

/// Matplotlib's "tab10" colours: distinct on white and for most colour-blind readers.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Tick labels and axis titles, px (at 11 px and under, ticks were hard to read).
const TICK_FONT: u32 = 14;
const AXIS_FONT: u32 = 16;

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

/// A tick label: whole numbers without decimals, others with at most four significant digits.
fn tick(v: f64) -> String {
    if (v - v.round()).abs() <= 1e-9 * v.abs().max(1.0) {
        return format!("{:.0}", v.round());
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let text = format!("{v:.digits$}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Width of the plotting area and of the legend column to its right (at least), and the height.
const PLOT_W: u32 = 760;
const LEGEND_W: u32 = 230;
const HEIGHT: u32 = 520;

/// Draws the chart into an SVG document: the plot, and its legend in a column to the right so
/// that it never covers data. Legend samples are drawn exactly as their series.
pub fn render(chart: &Chart) -> Result<String> {
    let axes = &chart.axes;
    let labelled: Vec<&Series> = chart
        .series
        .iter()
        .filter(|s| !s.label.is_empty())
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (PLOT_W + legend_width(&labelled), HEIGHT))
            .into_drawing_area();
        let to_err = |e: &dyn std::fmt::Display| anyhow!("plot {:?}: {e}", axes.title);
        root.fill(&WHITE).map_err(|e| to_err(&e))?;
        let (plot_area, legend_area) = root.split_horizontally(PLOT_W);
        let ((x0, x1), (y0, y1)) = data_ranges(&chart.series);
        let ((x0, x1), (y0, y1)) = if chart.equal_aspect {
            equal_aspect((x0, x1), (y0, y1))
        } else {
            ((x0, x1), (y0, y1))
        };
        let y_range = match chart.y_axis {
            YAxis::Up => y0..y1,
            YAxis::Down => y1..y0,
        };
        let mut plot = ChartBuilder::on(&plot_area)
            .caption(&axes.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(72)
            .build_cartesian_2d(x0..x1, y_range)
            .map_err(|e| to_err(&e))?;
        plot.configure_mesh()
            .x_desc(&axes.x)
            .y_desc(&axes.y)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", TICK_FONT))
            .axis_desc_style(("sans-serif", AXIS_FONT))
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.08))
            .draw()
            .map_err(|e| to_err(&e))?;
        draw_series(&mut plot, &chart.series).map_err(|e| to_err(&e))?;
        draw_legend(&legend_area, &labelled).map_err(|e| to_err(&e))?;
        root.present().map_err(|e| to_err(&e))?;
    }
    Ok(svg)
}

/// The legend column's width: wide enough for the longest label (≈ 9 px a character at 16 px,
/// after the 38 px sample), at least `LEGEND_W`; none without a label.
fn legend_width(labelled: &[&Series]) -> u32 {
    let longest = labelled
        .iter()
        .map(|s| s.label.chars().count())
        .max()
        .unwrap_or(0);
    if labelled.is_empty() {
        return 0;
    }
    let text_w = u32::try_from(longest)
        .unwrap_or(u32::MAX)
        .saturating_mul(9)
        .saturating_add(48);
    LEGEND_W.max(text_w)
}

/// The x and y ranges of every point; bars stand on 0 and are `BAR_WIDTH` wide, so the axes
/// hold their feet and edges.
fn data_ranges(series: &[Series]) -> ((f64, f64), (f64, f64)) {
    let bars = series.iter().filter(|s| s.style == Style::Bars);
    let bar_x = bars.clone().flat_map(|s| {
        s.points
            .iter()
            .flat_map(|p| [p.0 - BAR_WIDTH, p.0 + BAR_WIDTH])
    });
    let bar_feet = bars.flat_map(|s| s.points.first().map(|_| 0.0));
    let x = range(
        series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .chain(bar_x),
    );
    let y = range(
        series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(bar_feet),
    );
    (x, y)
}

type Plot<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;
type PlotError<'b> = DrawingAreaErrorKind<<SVGBackend<'b> as DrawingBackend>::ErrorType>;

/// The inner plotting area, px: the plot less its margins and label areas (as built above).
const INNER_W: f64 = (PLOT_W - 2 * 12 - 72) as f64;
const INNER_H: f64 = (HEIGHT - 2 * 12 - 46 - 30) as f64;

/// Ranges widened about their centres so that a unit of x and a unit of y are equally long in
/// the inner plotting area.
fn equal_aspect(x: (f64, f64), y: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    let per_px = ((x.1 - x.0) / INNER_W).max((y.1 - y.0) / INNER_H);
    let widen = |(lo, hi): (f64, f64), px: f64| {
        let (mid, half) = ((lo + hi) / 2.0, per_px * px / 2.0);
        (mid - half, mid + half)
    };
    (widen(x, INNER_W), widen(y, INNER_H))
}

/// Every series in its style, those in front last.
fn draw_series<'b>(plot: &mut Plot<'_, 'b>, series: &[Series]) -> Result<(), PlotError<'b>> {
    let ordered = series
        .iter()
        .filter(|s| !s.front)
        .chain(series.iter().filter(|s| s.front));
    for s in ordered {
        let (colour, width) = look(s);
        match s.style {
            Style::Line | Style::ThinLine | Style::Faint => plot.draw_series(LineSeries::new(
                s.points.iter().copied(),
                colour.stroke_width(width),
            )),
            Style::Markers => {
                plot.draw_series(s.points.iter().map(|&p| Circle::new(p, 2, colour.filled())))
            }
            Style::Bars => plot.draw_series(s.points.iter().map(|&(x, y)| {
                let half = BAR_WIDTH / 2.0;
                Rectangle::new([(x - half, 0.0), (x + half, y)], colour.filled())
            })),
        }?;
    }
    Ok(())
}

/// The legend: each labelled series' sample, drawn as the series is, and its label.
fn draw_legend<'b>(
    area: &DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    labelled: &[&Series],
) -> Result<(), PlotError<'b>> {
    for (i, s) in labelled.iter().enumerate() {
        let y = 48 + 22 * i as i32;
        let (colour, width) = look(s);
        match s.style {
            Style::Markers => area.draw(&Circle::new((19, y), 3, colour.filled())),
            Style::Bars => area.draw(&Rectangle::new([(10, y - 6), (28, y + 6)], colour.filled())),
            _ => area.draw(&PathElement::new(
                vec![(8, y), (30, y)],
                colour.stroke_width(width),
            )),
        }?;
        area.draw(&Text::new(
            s.label.clone(),
            (38, y - 7),
            ("sans-serif", 16).into_font(),
        ))?;
    }
    Ok(())
}

/// The colour and stroke width a series is drawn with (the legend uses the same).
fn look(s: &Series) -> (RGBAColor, u32) {
    let colour = PALETTE[s.colour % PALETTE.len()].to_rgba();
    match s.style {
        Style::Line => (colour, 2),
        Style::ThinLine => (colour.mix(0.6), 1),
        Style::Faint => (colour.mix(0.2), 1),
        Style::Markers => (colour.mix(0.7), 1),
        Style::Bars => (colour.mix(0.85), 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_aspect_makes_units_equally_long() {
        let ((x0, x1), (y0, y1)) = equal_aspect((0.0, 10.0), (0.0, 100.0));
        let (x_per_px, y_per_px) = ((x1 - x0) / INNER_W, (y1 - y0) / INNER_H);
        assert!((x_per_px - y_per_px).abs() < 1e-12, "{x_per_px} {y_per_px}");
        // The data still fit, centred.
        assert!(x0 <= 0.0 && x1 >= 10.0 && (y0 - 0.0).abs() < 1e-9 && (y1 - 100.0).abs() < 1e-9);
        assert!(((x0 + x1) / 2.0 - 5.0).abs() < 1e-12);
    }

    #[test]
    fn front_series_are_drawn_last() {
        let chart = Chart::new(
            "map",
            "x",
            "y",
            vec![
                Series::new("truth", vec![(0.0, 0.0), (1.0, 1.0)], Style::Line, 3).in_front(),
                Series::new("estimate", vec![(0.0, 1.0), (1.0, 0.0)], Style::Line, 0),
            ],
        );
        let svg = render(&chart).unwrap();
        // tab10's blue (estimate) is drawn before its red (truth).
        let blue = svg.find("#1F77B4").unwrap();
        let red = svg.find("#D62728").unwrap();
        assert!(blue < red, "{svg}");
    }

    #[test]
    fn ticks_drop_needless_decimals() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(340.0), "340");
        assert_eq!(tick(-2.0), "-2");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(0.0), "0");
    }

    #[test]
    fn image_charts_render_with_y_down_and_a_legend_column() {
        let chart = Chart::new(
            "boxes",
            "x (px)",
            "y (px, downward)",
            vec![
                Series::new("truth", vec![(0.0, 0.0), (10.0, 5.0)], Style::Line, 0),
                Series::new("", vec![(3.0, 4.0)], Style::Markers, 1),
            ],
        )
        .in_image_coordinates();
        let svg = render(&chart).unwrap();
        assert!(svg.contains("width=\"990\""), "legend column added");
        assert!(
            svg.contains(">\ntruth\n<"),
            "the legend names the labelled series"
        );
        assert_eq!(
            svg.matches("<circle").count(),
            1,
            "unlabelled markers get no legend entry"
        );
    }

    #[test]
    fn a_long_label_widens_the_legend_column() {
        let label = "Window B-spline, n by CV per scene"; // 34 characters
        let chart = Chart::new(
            "gaps",
            "x",
            "y",
            vec![Series::new(
                label,
                vec![(0.0, 0.0), (1.0, 1.0)],
                Style::Line,
                0,
            )],
        );
        let svg = render(&chart).unwrap();
        // 760 + 48 + 9 × 34 = 1114, wider than the 230 px default column.
        assert!(svg.contains("width=\"1114\""), "column sized to the label");
    }

    #[test]
    fn bars_stand_on_zero_with_one_rectangle_each_and_a_legend_swatch() {
        let bars = |label: &str, points: Vec<(f64, f64)>, colour| {
            Series::new(label, points, Style::Bars, colour)
        };
        let chart = Chart::new(
            "errors",
            "pass",
            "error (m)",
            vec![
                bars("a", vec![(1.0, 2.0), (2.0, 3.0)], 0),
                // Pass 1 of "b" formed no track: no bar there.
                bars("b", vec![(2.0 + BAR_WIDTH, 4.0)], 1),
            ],
        );
        let without = render(&Chart::new("empty", "pass", "error (m)", Vec::new())).unwrap();
        let svg = render(&chart).unwrap();
        // Three bars and two legend swatches more than the frame alone draws.
        let rects = |s: &str| s.matches("<rect").count();
        assert_eq!(rects(&svg) - rects(&without), 3 + 2, "{svg}");
        // The y axis reaches down to the bars' foot, 0, though every value is ≥ 2.
        assert!(svg.contains(">\n0\n<") || svg.contains(">0<"), "{svg}");
    }
}
