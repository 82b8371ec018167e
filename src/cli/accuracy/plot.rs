//! The error-vs-time plot of one scene: log-log, one marker per method, the Pareto front
//! (the methods no other method beats in both time and error) joined by a line.
//!
//! Two panels share the time axis: RMSE over all pixels and FLIP over the textured pixels
//! (all pixels when none is textured). A legend on the right numbers the methods.

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

/// One panel: `(seconds, error)` per method (the compared methods, ground truth excluded).
fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    title: &str,
    error_name: &str,
    points: &[(f64, f64)],
    labels: bool,
) -> PlotResult<()> {
    let positive = |&(t, e): &(f64, f64)| t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite();
    let (Some(x_range), Some(y_range)) = (
        log_range(points.iter().filter(|p| positive(p)).map(|p| p.0)),
        log_range(points.iter().filter(|p| positive(p)).map(|p| p.1)),
    ) else {
        // Nothing to plot (e.g. every error is zero).
        if labels {
            area.draw_text(
                &format!("{title}: no positive values to plot"),
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
            .caption(title, (FAMILY, 18))
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
        mesh.x_desc("seconds (median), log scale")
            .y_desc(format!("{error_name}, log scale"))
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .label_style((FAMILY, 13));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.light_line_style(WHITE).draw().map_err(drawing_error)?;

    // The Pareto front as a line under the markers.
    let front = pareto_front(points);
    let front_points: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| points[i])
        .filter(|p| positive(p))
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
    for (index, point) in points.iter().enumerate() {
        if !positive(point) {
            continue;
        }
        let colour = method_colour(index);
        chart
            .draw_series(std::iter::once(Circle::new(*point, 5, colour.filled())))
            .map_err(drawing_error)?;
        if labels {
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{}", index + 1),
                    *point,
                    (FAMILY, 12).into_font().color(&colour),
                )))
                .map_err(drawing_error)?;
        }
    }
    Ok(())
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
        draw_panel(&left, &title, "RMSE", &rmse, labels)?;
        let title = format!("{}: {flip_title}", report.name);
        draw_panel(&right, &title, "FLIP", &flip, labels)?;
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
