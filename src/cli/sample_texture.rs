//! `conetrace sample-texture`: filtered lookups for a CSV of queries, printed as CSV.
//!
//! Exists so the filters can be compared with OpenImageIO from outside the renderer
//! (tests/oiio_crosscheck.rs). Textures load as `ColorSpace::Linear` by default,
//! because OpenImageIO's texture system does no sRGB decoding.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::texture::{ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, WrapMode};

/// Arguments of `sample-texture`.
#[derive(clap::Args, Debug)]
pub struct SampleTextureArgs {
    /// Texture file (PNG, JPEG, OpenEXR or TIFF; maketx's mip-mapped .exr and .tx keep their levels).
    pub texture: PathBuf,
    /// CSV with header `s,t,dsdx,dtdx,dsdy,dtdy`, one lookup per row.
    #[arg(long)]
    pub queries: PathBuf,
    /// Filter: closest, bilinear, trilinear, aniso or ewa.
    #[arg(long, default_value = "aniso", value_parser = crate::cli::render_cmd::filter_parser())]
    pub filter: FilterMode,
    /// Wrap mode for both axes: periodic, clamp, black or mirror.
    #[arg(long, default_value = "periodic", value_parser = wrap_parser())]
    pub wrap: WrapMode,
    /// Anisotropy limit.
    #[arg(long, default_value_t = 16.0, allow_negative_numbers = true)]
    pub max_aniso: f32,
    /// How 8-bit colour is decoded: linear (as OIIO does) or srgb.
    #[arg(long, default_value = "linear")]
    pub color_space: ColorSpace,
}

/// Reads a query CSV (header `s,t,dsdx,dtdx,dsdy,dtdy`); errors name the file and line.
pub fn read_queries(path: &Path) -> Result<Vec<TextureQuery>, String> {
    let name = path.display();
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read queries: {e}"))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let header: Vec<String> = match lines.next() {
        Some((_, h)) => h
            .split(',')
            .map(|c| c.trim().to_ascii_lowercase())
            .collect(),
        None => return Err(format!("{name}: empty query file")),
    };
    if header != ["s", "t", "dsdx", "dtdx", "dsdy", "dtdy"] {
        return Err(format!(
            "{name}: header must be s,t,dsdx,dtdx,dsdy,dtdy, found '{}'",
            header.join(",")
        ));
    }
    let mut queries = Vec::new();
    for (i, line) in lines {
        let mut v = [0.0f32; 6];
        let mut fields = line.split(',');
        for (k, slot) in v.iter_mut().enumerate() {
            let field = fields
                .next()
                .ok_or_else(|| format!("{name}: line {}: expected 6 values", i + 1))?;
            *slot = field.trim().parse().map_err(|_| {
                format!(
                    "{name}: line {}: value {} '{}' is not a number",
                    i + 1,
                    k + 1,
                    field.trim()
                )
            })?;
        }
        if fields.next().is_some() {
            return Err(format!("{name}: line {}: more than 6 values", i + 1));
        }
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(format!(
                "{name}: line {}: s and t must be finite, found ({}, {})",
                i + 1,
                v[0],
                v[1]
            ));
        }
        queries.push(TextureQuery {
            s: v[0],
            t: v[1],
            dsdx: v[2],
            dtdx: v[3],
            dsdy: v[4],
            dtdy: v[5],
        });
    }
    Ok(queries)
}

/// `--wrap`'s values, listed in `--help` and in errors.
fn wrap_parser() -> impl clap::builder::TypedValueParser<Value = WrapMode> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(["periodic", "clamp", "black", "mirror"])
        .try_map(|name| name.parse::<WrapMode>())
}

/// Runs the command; `Err` is a one-line message naming the file and problem.
pub fn run(args: &SampleTextureArgs) -> Result<(), String> {
    // The same rule as `render --max-aniso`.
    if !(args.max_aniso.is_finite() && args.max_aniso >= 1.0) {
        return Err(format!(
            "--max-aniso must be a finite number >= 1, got {}",
            args.max_aniso
        ));
    }
    let texture = Texture::from_file(&args.texture, args.color_space).map_err(|e| e.to_string())?;
    let queries = read_queries(&args.queries)?;
    let opts = FilterOptions {
        filter: args.filter,
        wrap_s: args.wrap,
        wrap_t: args.wrap,
        max_aniso: args.max_aniso,
    };
    let mut out = String::with_capacity(32 * (queries.len() + 1));
    out.push_str("r,g,b,a\n");
    for q in &queries {
        let v = texture.sample(q, &opts);
        // `{}` on f32 prints the shortest string that reads back to the same bits.
        let _ = writeln!(out, "{},{},{},{}", v.x, v.y, v.z, v.w);
    }
    // A tile that could not be read gave zeros: no result is printed.
    if let Some(failure) = texture.tile_failure() {
        return Err(failure.to_string());
    }
    std::io::stdout()
        .lock()
        .write_all(out.as_bytes())
        .map_err(|e| format!("stdout: cannot write results: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_csv_is_parsed_and_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("q.csv");
        std::fs::write(&good, "s,t,dsdx,dtdx,dsdy,dtdy\n0.5,0.25,0,0,1e-3,-2\n").unwrap();
        let q = read_queries(&good).unwrap();
        assert_eq!(q.len(), 1);
        assert_eq!(q[0].dtdy, -2.0);
        let bad = dir.path().join("bad.csv");
        std::fs::write(&bad, "s,t,dsdx,dtdx,dsdy,dtdy\n0.5,x,0,0,0,0\n").unwrap();
        let e = read_queries(&bad).unwrap_err();
        assert!(e.contains("bad.csv") && e.contains("line 2"), "{e}");
    }

    /// A NaN or infinite s or t is refused with its line; it used to filter to NaN (or, with
    /// `closest`, to some texel).
    #[test]
    fn non_finite_texture_coordinates_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        for (row, value) in [("nan,0.5", "NaN"), ("0.5,inf", "inf"), ("-inf,0", "-inf")] {
            let path = dir.path().join("q.csv");
            let text = format!("s,t,dsdx,dtdx,dsdy,dtdy\n0.5,0.5,0,0,0,0\n{row},0,0,0,0\n");
            std::fs::write(&path, text).unwrap();
            let e = read_queries(&path).unwrap_err();
            assert!(e.contains("line 3") && e.contains("must be finite"), "{e}");
            assert!(e.contains(value), "{e}");
        }
    }
}
