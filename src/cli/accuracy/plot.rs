//! The error-vs-time plots of every accuracy mode: log-log panels, one marker per method
//! or row, the Pareto front (the points no other point beats in both time and error)
//! joined and ringed in red ([`draw_log_log_panel`]), two panels side by side (RMSE and
//! FLIP, [`draw_two_panels`]).
//!
//! The footprint mode's plot ([`draw_error_vs_time`]) numbers its methods and adds a legend
//! on the right; its FLIP panel is over the textured pixels (all pixels when none is
//! textured).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::font::FAMILY;
use super::report::SceneReport;

/// Width and height of the plot image in pixels.
pub const PLOT_SIZE: (u32, u32) = (1100, 460);

/// Indices of the Pareto-optimal points of `(time, error)` pairs, sorted by time: a point
/// is on the front when no other point is at least as fast and at least as accurate and
/// strictly better in one of them. Points with a non-finite coordinate are ignored.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let finite = |&(t, e): &(f64, f64)| t.is_finite() && e.is_finite();
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| finite(&points[i]))
        .filter(|&i| {
            let (t, e) = points[i];
            !points
                .iter()
                .enumerate()
                .any(|(j, p)| j != i && finite(p) && p.0 <= t && p.1 <= e && (p.0 < t || p.1 < e))
        })
        .collect();
    front.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
    front
}

/// A colour per method index, distinct for the sixteen methods.
fn method_colour(index: usize) -> RGBColor {
    const COLOURS: [RGBColor; 16] = [
        RGBColor(120, 0, 120),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 114, 178),
        RGBColor(0, 158, 115),
        RGBColor(0, 90, 50),
        RGBColor(204, 121, 167),
        RGBColor(213, 94, 0),
        RGBColor(150, 40, 40),
        RGBColor(175, 175, 175),
        RGBColor(110, 110, 110),
        RGBColor(20, 20, 20),
        RGBColor(0, 158, 115),
        RGBColor(0, 90, 50),
        RGBColor(150, 40, 40),
        RGBColor(90, 10, 10),
    ];
    COLOURS[index % COLOURS.len()]
}

type PlotResult<T> = Result<T, String>;

fn drawing_error<E: std::fmt::Debug>(error: E) -> String {
    format!("drawing the plot: {error:?}")
}

/// An axis label with three significant digits and no float noise (0.3, not
/// 0.30000000000000004).
pub fn short_number(value: f64) -> String {
    if !(value.is_finite() && value > 0.0) {
        return format!("{value}");
    }
    let decimals = (2 - value.log10().floor() as i32).max(0) as usize;
    let text = format!("{value:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Tick values 1, 2, 5 x 10^k inside `range`.
pub fn log_ticks(range: &std::ops::Range<f64>) -> Vec<f64> {
    if !(range.start > 0.0 && range.end > range.start && range.end.is_finite()) {
        return Vec::new();
    }
    let mut ticks = Vec::new();
    let mut decade = 10f64.powi(range.start.log10().floor() as i32);
    while decade <= range.end {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v >= range.start && v <= range.end {
                ticks.push(v);
            }
        }
        decade *= 10.0;
    }
    ticks
}

/// A log axis range covering `values` with some room on both sides.
fn log_range(values: impl Iterator<Item = f64>) -> Option<std::ops::Range<f64>> {
    let (low, high) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !low.is_finite() {
        return None;
    }
    Some(low / 1.6..high * 1.6)
}

/// One marker of a log-log error-against-time panel.
pub struct PlotPoint {
    pub seconds: f64,
    pub error: f64,
    /// Drawn beside the marker, in its colour, when labels are on.
    pub label: String,
    pub colour: RGBColor,
}

/// What a panel writes: its title, axis descriptions, what it says when nothing can be
/// plotted, and an optional reference row of zero error by construction (an exact or
/// analytic render), drawn as a labelled vertical line at its seconds because a log axis
/// cannot show an error of 0.
pub struct PanelText {
    pub title: String,
    pub x_desc: &'static str,
    pub y_desc: String,
    pub empty_note: &'static str,
    pub zero_error: Option<(f64, &'static str)>,
}

fn plottable(seconds: f64, error: f64) -> bool {
    seconds > 0.0 && error > 0.0 && seconds.is_finite() && error.is_finite()
}

/// One log-log panel: a marker per point at `(seconds, error)`, the Pareto front of all
/// points joined and ringed in red, points with a zero or non-finite coordinate left out.
pub fn draw_log_log_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    text: &PanelText,
    points: &[PlotPoint],
    labels: bool,
) -> PlotResult<()> {
    let shown: Vec<&PlotPoint> = points
        .iter()
        .filter(|p| plottable(p.seconds, p.error))
        .collect();
    let zero_seconds = text
        .zero_error
        .map(|(seconds, _)| seconds)
        .filter(|s| *s > 0.0 && s.is_finite());
    let (Some(x_range), Some(y_range)) = (
        log_range(shown.iter().map(|p| p.seconds).chain(zero_seconds)),
        log_range(shown.iter().map(|p| p.error)),
    ) else {
        if labels {
            area.draw_text(
                &format!("{}: {}", text.title, text.empty_note),
                &(FAMILY, 16).into_text_style(area),
                (20, 20),
            )
            .map_err(drawing_error)?;
        }
        return Ok(());
    };
    let mut builder = ChartBuilder::on(area);
    builder.margin(12);
    if labels {
        builder
            .caption(text.title.as_str(), (FAMILY, 18))
            .x_label_area_size(40)
            .y_label_area_size(64);
    }
    let mut chart = builder
        .build_cartesian_2d(
            x_range
                .clone()
                .log_scale()
                .with_key_points(log_ticks(&x_range)),
            y_range
                .clone()
                .log_scale()
                .with_key_points(log_ticks(&y_range)),
        )
        .map_err(drawing_error)?;
    let mut mesh = chart.configure_mesh();
    if labels {
        mesh.x_desc(text.x_desc)
            .y_desc(text.y_desc.as_str())
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .label_style((FAMILY, 13));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.light_line_style(WHITE).draw().map_err(drawing_error)?;

    if let (Some(seconds), Some((_, name))) = (zero_seconds, text.zero_error) {
        chart
            .draw_series(LineSeries::new(
                [(seconds, y_range.start), (seconds, y_range.end)],
                ShapeStyle::from(&BLACK).stroke_width(2),
            ))
            .map_err(drawing_error)?;
        if labels {
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{name} (error 0)"),
                    (seconds, y_range.end / 1.3),
                    (FAMILY, 13).into_font(),
                )))
                .map_err(drawing_error)?;
        }
    }

    // The Pareto front as a line under the markers.
    let pairs: Vec<(f64, f64)> = points.iter().map(|p| (p.seconds, p.error)).collect();
    let front_points: Vec<(f64, f64)> = pareto_front(&pairs)
        .iter()
        .map(|&i| pairs[i])
        .filter(|&(t, e)| plottable(t, e))
        .collect();
    chart
        .draw_series(LineSeries::new(
            front_points.iter().copied(),
            ShapeStyle::from(&RED).stroke_width(2),
        ))
        .map_err(drawing_error)?;
    chart
        .draw_series(
            front_points
                .iter()
                .map(|&p| Circle::new(p, 9, ShapeStyle::from(&RED).stroke_width(2))),
        )
        .map_err(drawing_error)?;
    for point in shown {
        let at = (point.seconds, point.error);
        chart
            .draw_series(std::iter::once(Circle::new(at, 5, point.colour.filled())))
            .map_err(drawing_error)?;
        if labels {
            chart
                .draw_series(std::iter::once(Text::new(
                    point.label.clone(),
                    at,
                    (FAMILY, 12).into_font().color(&point.colour),
                )))
                .map_err(drawing_error)?;
        }
    }
    Ok(())
}

/// A plot of [`PLOT_SIZE`] as RGB8 pixels with two panels side by side (RMSE on the left,
/// FLIP on the right in every mode).
pub fn draw_two_panels(
    left: (&PanelText, &[PlotPoint]),
    right: (&PanelText, &[PlotPoint]),
    labels: bool,
) -> PlotResult<Vec<u8>> {
    let (width, height) = PLOT_SIZE;
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing_error)?;
        let (left_area, right_area) = root.split_horizontally(width / 2);
        draw_log_log_panel(&left_area, left.0, left.1, labels)?;
        draw_log_log_panel(&right_area, right.0, right.1, labels)?;
        root.present().map_err(drawing_error)?;
    }
    Ok(buffer)
}

/// The footprint mode's points: the methods numbered from 1, each in its colour.
fn numbered_points(points: &[(f64, f64)]) -> Vec<PlotPoint> {
    points
        .iter()
        .enumerate()
        .map(|(index, &(seconds, error))| PlotPoint {
            seconds,
            error,
            label: format!("{}", index + 1),
            colour: method_colour(index),
        })
        .collect()
}

/// The footprint mode's panel text: methods against the supersampled ground truth.
fn footprint_text(title: &str, error_name: &str) -> PanelText {
    PanelText {
        title: title.to_string(),
        x_desc: "seconds (median), log scale",
        y_desc: format!("{error_name}, log scale"),
        empty_note: "no positive values to plot",
        zero_error: None,
    }
}

/// The legend: one numbered line per method, in its colour, front members marked.
fn draw_legend(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    names: &[String],
    on_front: &[bool],
) -> PlotResult<()> {
    let style = |colour: RGBColor| (FAMILY, 14).into_font().color(&colour);
    area.draw_text(
        "red ring: RMSE Pareto front",
        &style(BLACK).into_text_style(area),
        (4, 30),
    )
    .map_err(drawing_error)?;
    for (index, name) in names.iter().enumerate() {
        let y = 56 + index as i32 * 22;
        area.draw(&Circle::new((10, y + 7), 5, method_colour(index).filled()))
            .map_err(drawing_error)?;
        if on_front.get(index) == Some(&true) {
            area.draw(&Circle::new(
                (10, y + 7),
                8,
                ShapeStyle::from(&RED).stroke_width(2),
            ))
            .map_err(drawing_error)?;
        }
        area.draw_text(
            &format!("{} {name}", index + 1),
            &style(method_colour(index)).into_text_style(area),
            (24, y),
        )
        .map_err(drawing_error)?;
    }
    Ok(())
}

/// Draws the plot of `report` into an RGB8 buffer of [`PLOT_SIZE`]; labels are drawn when
/// `labels` is true (a font is registered, see [`super::font::labels_available`]).
pub fn draw_error_vs_time(report: &SceneReport, labels: bool) -> PlotResult<Vec<u8>> {
    let (width, height) = PLOT_SIZE;
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    let compared: Vec<_> = report.rows.iter().filter(|r| r.error.is_some()).collect();
    let names: Vec<String> = compared.iter().map(|r| r.method.label()).collect();
    let rmse: Vec<(f64, f64)> = compared
        .iter()
        .map(|r| (r.seconds, r.error.map_or(f64::NAN, |e| e.rmse)))
        .collect();
    let any_textured = compared.iter().any(|r| r.textured_error.is_some());
    let flip: Vec<(f64, f64)> = compared
        .iter()
        .map(|r| {
            let metrics = if any_textured {
                r.textured_error
            } else {
                r.error
            };
            (r.seconds, metrics.map_or(f64::NAN, |e| e.flip))
        })
        .collect();
    let flip_title = if any_textured {
        "FLIP (mean), textured pixels"
    } else {
        "FLIP (mean), all pixels"
    };
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing_error)?;
        let (charts, legend) = root.split_horizontally(width - 250);
        let (left, right) = charts.split_horizontally((width - 250) / 2);
        let title = format!("{}: RMSE, all pixels", report.name);
        draw_log_log_panel(
            &left,
            &footprint_text(&title, "RMSE"),
            &numbered_points(&rmse),
            labels,
        )?;
        let title = format!("{}: {flip_title}", report.name);
        draw_log_log_panel(
            &right,
            &footprint_text(&title, "FLIP"),
            &numbered_points(&flip),
            labels,
        )?;
        if labels {
            let front = pareto_front(&rmse);
            let on_front: Vec<bool> = (0..names.len()).map(|i| front.contains(&i)).collect();
            draw_legend(&legend, &names, &on_front)?;
        }
        root.present().map_err(drawing_error)?;
    }
    Ok(buffer)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_the_undominated_points_sorted_by_time() {
        let points = [
            (1.0, 0.5),      // 0: fastest
            (2.0, 0.6),      // 1: dominated by 0
            (4.0, 0.1),      // 2: front
            (3.0, 0.3),      // 3: front
            (4.0, 0.2),      // 4: dominated by 2
            (f64::NAN, 0.0), // 5: ignored
            (8.0, 0.1),      // 6: dominated by 2 (same error, slower)
        ];
        assert_eq!(pareto_front(&points), vec![0, 3, 2]);
        assert!(pareto_front(&[]).is_empty());
        // Identical points are both on the front (neither is strictly better).
        assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), vec![0, 1]);
    }

    #[test]
    fn log_ticks_step_1_2_5() {
        assert_eq!(log_ticks(&(0.015..0.3)), vec![0.02, 0.05, 0.1, 0.2]);
        assert!(log_ticks(&(0.0..1.0)).is_empty());
    }

    #[test]
    fn axis_labels_are_short() {
        assert_eq!(short_number(0.30000000000000004), "0.3");
        assert_eq!(short_number(0.0123456), "0.0123");
        assert_eq!(short_number(1.0), "1");
        assert_eq!(short_number(250.0), "250");
        assert_eq!(short_number(1234.6), "1235");
    }
}
