//! What a pipeline shows in the report: tables of formatted cells and charts as data. xtask
//! renders the charts (SVG) and writes the report (HTML and Markdown).

/// A report section, one per scenario.
#[derive(Debug, Clone, Default)]
pub struct Section {
    /// Heading.
    pub title: String,
    /// A paragraph of Markdown-free text: what is shown and how to read it.
    pub summary: String,
    /// Tables in order.
    pub tables: Vec<Table>,
    /// Figures in order.
    pub figures: Vec<Figure>,
}

/// A table of already-formatted cells.
#[derive(Debug, Clone, Default)]
pub struct Table {
    /// Caption.
    pub caption: String,
    /// Column headers.
    pub header: Vec<String>,
    /// Rows; each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with the given caption and header.
    pub fn new(caption: &str, header: &[&str]) -> Self {
        Self {
            caption: caption.to_string(),
            header: header.iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }
}

/// A chart with its file name and caption.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem (unique within the section).
    pub name: String,
    /// Caption.
    pub caption: String,
    /// What to draw.
    pub chart: Chart,
}

impl Figure {
    /// A figure from its parts.
    pub fn new(name: &str, caption: &str, chart: Chart) -> Self {
        Self {
            name: name.to_string(),
            caption: caption.to_string(),
            chart,
        }
    }
}

/// Labelled series on one pair of axes.
#[derive(Debug, Clone)]
pub struct Chart {
    /// Title and axis labels.
    pub axes: Axes,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Which way y grows on the page.
    pub y_axis: YAxis,
    /// One unit of x is as long on the page as one unit of y (maps and polar plots, where an
    /// angle or a circle must look like one).
    pub equal_aspect: bool,
}

impl Chart {
    /// A chart titled `title` with axis labels `x` and `y` (give units, e.g. "error (px)").
    pub fn new(title: &str, x: &str, y: &str, series: Vec<Series>) -> Self {
        Self {
            axes: Axes {
                title: title.to_string(),
                x: x.to_string(),
                y: y.to_string(),
            },
            series,
            y_axis: YAxis::Up,
            equal_aspect: false,
        }
    }

    /// The same chart at equal aspect: the ranges widen so that a unit of x and of y are
    /// equally long on the page.
    pub fn with_equal_aspect(mut self) -> Self {
        self.equal_aspect = true;
        self
    }

    /// The same chart in image coordinates: y grows downward, as in the image.
    pub fn in_image_coordinates(mut self) -> Self {
        self.y_axis = YAxis::Down;
        self
    }
}

/// Which way a chart's y axis grows on the page.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YAxis {
    /// Upward, as in a graph.
    Up,
    /// Downward, as in image coordinates (row 0 at the top).
    Down,
}

/// A chart's title and axis labels.
#[derive(Debug, Clone)]
pub struct Axes {
    /// Title above the chart.
    pub title: String,
    /// x-axis label.
    pub x: String,
    /// y-axis label.
    pub y: String,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points.
    Line,
    /// A thin, lighter polyline.
    ThinLine,
    /// A very light hairline, for background structure (map links, grids) that data drawn
    /// over it must stand out from.
    Faint,
    /// Small circles.
    Markers,
    /// Filled bars from 0 to each point's y, [`BAR_WIDTH`] wide and centred on its x. Grouped
    /// bars are series whose x values are offset by multiples of [`BAR_WIDTH`]; a point left
    /// out is a missing bar.
    Bars,
}

/// Width of a [`Style::Bars`] bar in x-axis units.
pub const BAR_WIDTH: f64 = 0.25;

/// One labelled series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label; empty for no legend entry.
    pub label: String,
    /// The points.
    pub points: Vec<(f64, f64)>,
    /// How to draw it.
    pub style: Style,
    /// Palette index (same index, same colour).
    pub colour: usize,
    /// Drawn after every series that is not (truth over the estimates that would hide it).
    pub front: bool,
}

impl Series {
    /// A series from its parts.
    pub fn new(label: &str, points: Vec<(f64, f64)>, style: Style, colour: usize) -> Self {
        Self {
            label: label.to_string(),
            points,
            style,
            colour,
            front: false,
        }
    }

    /// The same series drawn over the others.
    pub fn in_front(mut self) -> Self {
        self.front = true;
        self
    }
}

/// Formats a number for a table: 4 significant digits, plain or scientific.
pub fn fmt_num(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e9 {
        // Counts and other whole numbers print as integers.
        return format!("{v:.0}");
    }
    if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        let digits = if v == 0.0 {
            0
        } else {
            (3 - v.abs().log10().floor() as i32).max(0)
        };
        format!("{v:.prec$}", prec = digits as usize)
    } else {
        format!("{v:.3e}")
    }
}

/// A report text from a template: every `{name}` of `template` replaced by its value (report
/// prose lives in text files beside its pipeline, not in long string literals). A placeholder
/// without a value, or a value without its placeholder, is a bug in the pipeline, caught in
/// debug builds.
pub fn fill(template: &str, values: &[(&str, String)]) -> String {
    let mut out = template.to_string();
    for (name, value) in values {
        let key = format!("{{{name}}}");
        debug_assert!(out.contains(&key), "the template has no {key}");
        out = out.replace(&key, value);
    }
    debug_assert!(
        !out.contains('{') || !out.contains('}'),
        "a placeholder of the template has no value: {out}"
    );
    out
}
