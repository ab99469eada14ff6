//! PNG charts for the validation report (plotters with an embedded DejaVu font, so plotting needs
//! no system fonts).

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

/// One curve or point set.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Draw markers instead of a line.
    pub markers: bool,
    /// Dashed look (drawn thinner), e.g. for a second quantity of the same model.
    pub thin: bool,
}

/// A 2-D chart description.
pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(0, 0, 0),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(23, 190, 207),
];

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration only fails on an unparsable font; the embedded one parses.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (1e-3, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 0.5 * lo.abs().max(1e-12) };
        (lo - pad, hi + pad)
    }
}

/// Tick text: plain decimals in the everyday range, scientific notation outside it. A tick within
/// round-off of zero on an axis spanning `span` (the sum of steps that should give 0, e.g. −5.55e-17)
/// reads 0 (`span` 0 on a log axis, whose ticks are never round-off).
fn tick(v: f64, span: f64) -> String {
    let v = if v.abs() <= 1e-9 * span.abs() { 0.0 } else { v };
    let a = v.abs();
    if a == 0.0 || (1e-2..1e4).contains(&a) {
        format!("{v:.3}").trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.2e}")
    }
}

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("plot: {e:?}")
}

/// Draws `chart` into a 900×600 PNG at `path`.
pub fn draw(path: &Path, chart: &Chart) -> Result<(), String> {
    draw_panels(path, std::slice::from_ref(chart), 1)
}

/// Draws `charts` side by side into one PNG at `path`, `columns` panels per row, each 900×600.
pub fn draw_panels(path: &Path, charts: &[Chart], columns: usize) -> Result<(), String> {
    register_font();
    let columns = columns.clamp(1, charts.len().max(1));
    let rows = charts.len().div_ceil(columns).max(1);
    let (w, h) = (900 * columns as u32, 600 * rows as u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        for (area, chart) in root.split_evenly((rows, columns)).iter().zip(charts) {
            draw_on(area, chart)?;
        }
        root.present().map_err(err)?;
    }
    let file = std::fs::File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()
        .and_then(|mut wr| wr.write_image_data(&buf))
        .map_err(|e| format!("cannot encode {}: {e}", path.display()))
}

/// Draws one chart on a drawing area.
fn draw_on<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    chart: &Chart,
) -> Result<(), String> {
    {
        let xs = range(chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)), chart.log_x);
        let ys = range(chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), chart.log_y);
        let mut builder = ChartBuilder::on(root);
        builder
            .caption(chart.title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80);
        // plotters types differ per axis kind, so the four combinations are spelled out.
        macro_rules! body {
            ($ctx:expr) => {{
                let mut ctx = $ctx;
                ctx.configure_mesh()
                    .x_desc(chart.x_label)
                    .y_desc(chart.y_label)
                    .x_label_formatter(&|v| tick(*v, if chart.log_x { 0.0 } else { xs.1 - xs.0 }))
                    .y_label_formatter(&|v| tick(*v, if chart.log_y { 0.0 } else { ys.1 - ys.0 }))
                    .draw()
                    .map_err(err)?;
                for (i, s) in chart.series.iter().enumerate() {
                    let color = PALETTE[i % PALETTE.len()];
                    let width = if s.thin { 1 } else { 2 };
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|p| {
                            p.0.is_finite()
                                && p.1.is_finite()
                                && (!chart.log_x || p.0 > 0.0)
                                && (!chart.log_y || p.1 > 0.0)
                        })
                        .collect();
                    // A series without a label (e.g. a second segment of a labelled one) gets no
                    // legend entry.
                    if s.markers {
                        let a = ctx
                            .draw_series(pts.iter().map(|p| Circle::new(*p, 5, color.filled())))
                            .map_err(err)?;
                        if !s.label.is_empty() {
                            a.label(s.label.clone())
                                .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
                        }
                    } else {
                        let a =
                            ctx.draw_series(LineSeries::new(pts, color.stroke_width(width))).map_err(err)?;
                        if !s.label.is_empty() {
                            a.label(s.label.clone()).legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                            });
                        }
                    }
                }
                ctx.configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(err)?;
            }};
        }
        match (chart.log_x, chart.log_y) {
            (false, false) => body!(builder.build_cartesian_2d(xs.0..xs.1, ys.0..ys.1).map_err(err)?),
            (true, false) => {
                body!(builder.build_cartesian_2d((xs.0..xs.1).log_scale(), ys.0..ys.1).map_err(err)?)
            }
            (false, true) => {
                body!(builder.build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale()).map_err(err)?)
            }
            (true, true) => {
                body!(builder
                    .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
                    .map_err(err)?)
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::tick;

    /// A tick at round-off of zero on a linear axis reads 0; real small values, and every tick of a
    /// log axis (span 0), keep their digits.
    #[test]
    fn tick_text_drops_round_off_at_zero_only() {
        assert_eq!(tick(-5.55e-17, 1.3), "0");
        assert_eq!(tick(0.25, 1.3), "0.25");
        assert_eq!(tick(1e-12, 0.0), "1.00e-12");
        assert_eq!(tick(2e-6, 1e-5), "2.00e-6");
    }
}
