//! The classic Bezier patch text format (`.bpt`), in which the Utah teapot's 32 patches
//! are usually published.
//!
//! Whitespace-separated numbers: the patch count, then for each patch its degrees in u and
//! v (`3 3` for bicubic; 1 to 3 each) followed by `(degree_u + 1) (degree_v + 1)` points of
//! three coordinates, row by row with u fastest. Lower degrees are elevated to bicubic
//! exactly (`basis::elevate_to_bicubic`). Nothing may follow the last patch.

use glam::Vec3;

use super::basis::elevate_to_bicubic;

/// Reads the token stream with the line each token is on, for messages.
struct Tokens<'a> {
    tokens: Vec<(usize, &'a str)>,
    next: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Tokens<'a> {
        let tokens = text
            .lines()
            .enumerate()
            .flat_map(|(line, l)| l.split_whitespace().map(move |t| (line + 1, t)))
            .collect();
        Tokens { tokens, next: 0 }
    }

    fn line(&self) -> usize {
        self.tokens
            .get(self.next)
            .or(self.tokens.last())
            .map_or(1, |t| t.0)
    }

    fn take(&mut self, what: &str) -> Result<&'a str, String> {
        let token = self
            .tokens
            .get(self.next)
            .ok_or_else(|| format!("line {}: ends where {what} was expected", self.line()))?;
        self.next += 1;
        Ok(token.1)
    }

    fn count(&mut self, what: &str) -> Result<usize, String> {
        let line = self.line();
        let token = self.take(what)?;
        token
            .parse::<usize>()
            .map_err(|_| format!("line {line}: {what} must be a whole number, not '{token}'"))
    }

    fn number(&mut self, what: &str) -> Result<f32, String> {
        let line = self.line();
        let token = self.take(what)?;
        let value = token
            .parse::<f32>()
            .map_err(|_| format!("line {line}: {what} must be a number, not '{token}'"))?;
        if !value.is_finite() {
            return Err(format!("line {line}: {what} is not finite ('{token}')"));
        }
        Ok(value)
    }
}

/// The bicubic control points of every patch in `text`, or a one-line reason naming the
/// line at fault.
pub fn parse_bpt(text: &str) -> Result<Vec<[Vec3; 16]>, String> {
    let mut tokens = Tokens::new(text);
    let count = tokens.count("the patch count")?;
    if count == 0 {
        return Err("line 1: the patch count is 0".into());
    }
    let mut patches = Vec::with_capacity(count.min(1 << 16));
    let mut split = SplitPoint::default();
    for patch in 0..count {
        let line = tokens.line();
        let degree_u = tokens.count(&format!("patch {patch}'s degree in u"))?;
        let degree_v = tokens.count(&format!("patch {patch}'s degree in v"))?;
        if !(1..=3).contains(&degree_u) || !(1..=3).contains(&degree_v) {
            return Err(format!(
                "line {line}: patch {patch} has degree {degree_u} {degree_v}; each must be 1 to 3"
            ));
        }
        let n = (degree_u + 1) * (degree_v + 1);
        let mut points = Vec::with_capacity(n);
        for k in 0..n {
            let what = format!("coordinate of patch {patch}'s control point {k}");
            let first_line = tokens.line();
            let x = tokens.number(&what).map_err(|e| split.explain(e))?;
            let y = tokens.number(&what).map_err(|e| split.explain(e))?;
            let z = tokens.number(&what).map_err(|e| split.explain(e))?;
            if split.first.is_none() && tokens.tokens[tokens.next - 1].0 != first_line {
                split.first = Some(format!(
                    "patch {patch}'s control point {k} starts on line {first_line} and ends on \
                     line {}",
                    tokens.tokens[tokens.next - 1].0
                ));
            }
            points.push(Vec3::new(x, y, z));
        }
        let Some(bicubic) = elevate_to_bicubic(degree_u, degree_v, &points) else {
            return Err(format!("line {line}: patch {patch} has a bad control grid"));
        };
        patches.push(bicubic);
    }
    if tokens.next < tokens.tokens.len() {
        return Err(split.explain(format!(
            "line {}: text after the {count} patches the count line announces",
            tokens.line()
        )));
    }
    Ok(patches)
}

/// The first control point whose three numbers are not on one line. The format only asks
/// for whitespace between numbers, but files put one point on each line, so a split point is
/// usually a line with a number missing or extra, and the error it leads to (too few or too
/// many numbers at the end) is reported with it.
#[derive(Default)]
struct SplitPoint {
    first: Option<String>,
}

impl SplitPoint {
    fn explain(&self, error: String) -> String {
        match &self.first {
            Some(point) => format!("{error} ({point}: a number missing or extra there?)"),
            None => error,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE_FLAT: &str = "1\n3 3\n0 0 0\n1 0 0\n2 0 0\n3 0 0\n0 1 0\n1 1 0\n2 1 0\n3 1 0\n\
                            0 2 0\n1 2 0\n2 2 0\n3 2 0\n0 3 0\n1 3 0\n2 3 0\n3 3 0\n";

    #[test]
    fn a_bicubic_patch_reads_row_by_row() {
        let patches = parse_bpt(ONE_FLAT).unwrap();
        assert_eq!(patches.len(), 1);
        assert_eq!(patches[0][5], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(patches[0][12], Vec3::new(0.0, 3.0, 0.0));
    }

    #[test]
    fn the_shipped_teapot_has_32_patches() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/models/teapot.bpt");
        let text = std::fs::read_to_string(path).expect("assets/models/teapot.bpt is shipped");
        let patches = parse_bpt(&text).unwrap();
        assert_eq!(patches.len(), 32);
        // The rim's first control point and the bottom's collapsed centre.
        assert_eq!(patches[0][0], Vec3::new(1.4, 0.0, 2.4));
        assert_eq!(patches[28][0], Vec3::ZERO);
    }

    /// A line with a number missing shifts every number after it; the error says where the
    /// first point was split over two lines, not only that the file ended early or late.
    #[test]
    fn a_line_with_a_number_missing_or_extra_is_pointed_at() {
        let missing = ONE_FLAT.replace("\n1 1 0\n", "\n1 1\n");
        let e = parse_bpt(&missing).unwrap_err();
        assert!(e.contains("ends where"), "{e}");
        assert!(e.contains("control point 5 starts on line 8"), "{e}");
        let extra = format!("{ONE_FLAT}0 0 0\n").replace("\n2 2 0\n", "\n2 2 0 7\n");
        let extra = extra.replace("\n3 3 0\n0 0 0\n", "\n3 3 0\n");
        let e = parse_bpt(&extra).unwrap_err();
        assert!(e.contains("text after"), "{e}");
        assert!(e.contains("control point 11 starts on line 13"), "{e}");
    }

    #[test]
    fn bad_files_name_the_line() {
        let short = &ONE_FLAT[..ONE_FLAT.len() - 6];
        assert!(parse_bpt(short).unwrap_err().contains("ends where"));
        let nan = ONE_FLAT.replace("2 2 0", "2 nan 0");
        let e = parse_bpt(&nan).unwrap_err();
        assert!(e.starts_with("line 13:") && e.contains("not finite"), "{e}");
        let extra = format!("{ONE_FLAT}7\n");
        assert!(parse_bpt(&extra).unwrap_err().contains("text after"));
        let degree = ONE_FLAT.replace("3 3\n", "4 3\n");
        assert!(parse_bpt(&degree).unwrap_err().contains("degree 4 3"));
        assert!(parse_bpt("0\n").unwrap_err().contains("count is 0"));
    }
}
