//! The per-scene results of `conetrace accuracy` as data, CSV and a markdown table.

use crate::film::PixelRect;

use super::methods::Method;
use super::metrics::ErrorMetrics;

/// One rendered method of one scene: its cost and its error against the ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Strategy, filter and samples per pixel.
    pub method: Method,
    /// Median render time over the timed runs, seconds.
    pub seconds: f64,
    /// Every timed render's seconds, in run order.
    pub run_seconds: Vec<f64>,
    /// Rays of every kind (camera, shadow, reflection, refraction).
    pub rays: u64,
    /// Filtered texture lookups.
    pub texture_lookups: u64,
    /// Distinct 64x64 texture tiles touched, summed over textures and mip levels.
    pub tiles_touched: u64,
    /// Error against the ground truth; `None` for the ground-truth row itself.
    pub error: Option<ErrorMetrics>,
    /// The same over the textured pixels; `None` for the ground truth or when no pixel is
    /// textured.
    pub textured_error: Option<ErrorMetrics>,
    /// `seconds` over the fastest row's seconds in this scene.
    pub relative_time: f64,
}

/// Everything measured for one scene.
#[derive(Clone, Debug)]
pub struct SceneReport {
    /// File stem (or `default` for the built-in scene): the output files' prefix.
    pub name: String,
    /// Where the scene came from (path, or the built-in label).
    pub source: String,
    /// Image width of every render.
    pub width: u32,
    /// Image height of every render.
    pub height: u32,
    /// Timed runs per row.
    pub runs: usize,
    /// Worker threads of the renders.
    pub threads: usize,
    /// Pixels whose first camera path looked up a surface texture.
    pub textured_pixels: usize,
    /// The region shown in the crop image.
    pub crop: PixelRect,
    /// The ground truth row first, then the compared methods in order.
    pub rows: Vec<Row>,
}

/// The CSV header; one line per [`Row`] follows.
pub const CSV_HEADER: &str =
    "scene,strategy,filter,spp,seconds,rays,texture_lookups,tiles_touched,\
rmse,psnr_db,flip,rmse_textured,psnr_textured_db,flip_textured,relative_time";

fn number(value: f64, decimals: usize) -> String {
    if value.is_nan() {
        String::new()
    } else if value.is_infinite() {
        if value > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        format!("{value:.decimals$}")
    }
}

fn metric_cells(metrics: Option<ErrorMetrics>) -> [String; 3] {
    match metrics {
        Some(m) => [number(m.rmse, 6), number(m.psnr, 3), number(m.flip, 6)],
        None => [String::new(), String::new(), String::new()],
    }
}

/// The rows as CSV (header first). Error cells are empty for the ground truth row and for
/// textured metrics of a scene without textured pixels; PSNR of identical images is `inf`.
pub fn csv(report: &SceneReport) -> String {
    let mut text = String::from(CSV_HEADER);
    text.push('\n');
    for row in &report.rows {
        let [rmse, psnr, flip] = metric_cells(row.error);
        let [trmse, tpsnr, tflip] = metric_cells(row.textured_error);
        text.push_str(&format!(
            "{},{},{},{},{},{},{},{},{rmse},{psnr},{flip},{trmse},{tpsnr},{tflip},{}\n",
            report.name,
            row.method.lod,
            row.method.filter,
            row.method.spp,
            number(row.seconds, 6),
            row.rays,
            row.texture_lookups,
            row.tiles_touched,
            number(row.relative_time, 3),
        ));
    }
    text
}

fn markdown_cells(metrics: Option<ErrorMetrics>, reference: bool) -> String {
    match metrics {
        Some(m) => format!(
            "{} | {} | {}",
            number(m.rmse, 4),
            number(m.psnr, 2),
            number(m.flip, 4)
        ),
        None if reference => "reference | | ".to_string(),
        None => "— | — | —".to_string(),
    }
}

/// The rows as a markdown table with a heading line naming the scene and the settings.
pub fn markdown(report: &SceneReport) -> String {
    let pixels = report.width as usize * report.height as usize;
    let mut text = format!(
        "### {name}\n\n`{source}` at {w}x{h}; {textured} of {pixels} pixels textured; times are the \
         median of {runs} interleaved runs on {threads} threads. Errors are against the ground \
         truth (first row), on display values (sRGB after tone mapping).\n\n",
        name = report.name,
        source = report.source,
        w = report.width,
        h = report.height,
        textured = report.textured_pixels,
        runs = report.runs,
        threads = report.threads,
    );
    text.push_str(
        "| strategy | filter | spp | seconds | rays | texture lookups | tiles touched | RMSE | \
         PSNR dB | FLIP | RMSE textured | PSNR textured dB | FLIP textured | time / fastest |\n",
    );
    text.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (index, row) in report.rows.iter().enumerate() {
        let reference = index == 0 && row.error.is_none();
        text.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            row.method.lod,
            row.method.filter,
            row.method.spp,
            number(row.seconds, 4),
            row.rays,
            row.texture_lookups,
            row.tiles_touched,
            markdown_cells(row.error, reference),
            markdown_cells(row.textured_error, reference),
            number(row.relative_time, 2),
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::footprint::LodStrategy;
    use crate::texture::FilterMode;

    fn row(spp: u32, error: Option<ErrorMetrics>) -> Row {
        Row {
            method: Method {
                lod: LodStrategy::Cone,
                filter: FilterMode::Ewa,
                spp,
            },
            seconds: 0.5,
            run_seconds: vec![0.5],
            rays: 100,
            texture_lookups: 40,
            tiles_touched: 7,
            error,
            textured_error: None,
            relative_time: 1.0,
        }
    }

    #[test]
    fn csv_has_a_header_and_one_line_per_row_with_empty_reference_cells() {
        let report = SceneReport {
            name: "s".into(),
            source: "s.toml".into(),
            width: 4,
            height: 2,
            runs: 1,
            threads: 1,
            textured_pixels: 0,
            crop: PixelRect::default(),
            rows: vec![
                row(64, None),
                row(
                    1,
                    Some(ErrorMetrics {
                        rmse: 0.1,
                        psnr: 20.0,
                        flip: 0.05,
                    }),
                ),
            ],
        };
        let text = csv(&report);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        let columns = CSV_HEADER.split(',').count();
        assert!(lines.iter().all(|l| l.split(',').count() == columns));
        assert_eq!(
            lines[2],
            "s,cone,ewa,1,0.500000,100,40,7,0.100000,20.000,0.050000,,,,1.000"
        );
        assert!(lines[1].contains(",,,,,,"));
        let table = markdown(&report);
        assert_eq!(table.lines().filter(|l| l.starts_with("| cone")).count(), 2);
        assert!(table.contains("reference"));
    }
}
