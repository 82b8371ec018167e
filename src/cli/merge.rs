//! `conetrace merge PARTS... -o out.exr`: the image of a render split into parts
//! (`--region`, `--samples`, `--part`), equal bit for bit to rendering it on one machine.
//!
//! How each channel is combined:
//! - colour (`R G B`): a part holding every sample of its pixels has their final values,
//!   copied as they are. Parts holding sample ranges carry the exact fixed-point sums of
//!   their samples (`film::sample_sum`, channels `sum.*`); the sums of a pixel's parts are
//!   added (integer addition: any grouping gives the same sum) and the pixel becomes
//!   `mean_of_sum(sum, spp)`, the very function the whole render applies to its own sum.
//!   The `sum.*` channels are not written to the result.
//! - alpha and the AOVs (depth, normal, albedo, uv, texture footprint, lod, footprint):
//!   they describe each pixel's first camera sample (sample 0), so they come from the part
//!   whose sample range starts at 0. Other parts hold placeholders for them, ignored.
//!
//! Refused with one line and exit status 2, writing nothing: a file that cannot be read
//! whole (missing, truncated, not an EXR), an interrupted part, parts of different scenes,
//! files or options (the `conetrace.option.*`, `conetrace.input.*` and `conetrace.version`
//! header signature, `cli::resume`), parts whose regions overlap while their sample ranges
//! overlap (duplicates included), and pixels left with fewer than all their samples (a
//! missing region or sample range). The result is written atomically (`film::OutputSet`).

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use clap::Args;

use crate::cli::resume::{encode_tiles, is_signature_attribute, TILES_DONE_ATTRIBUTE};
use crate::cli::CommandError;
use crate::film::partial::{
    format_sample_range, ImageWindow, SAMPLES_ATTRIBUTE, SAMPLE_WEIGHT_ATTRIBUTE,
};
use crate::film::{self, sample_sum, ExrAttributes, Film, Layer, OutputSet, PixelRect};

#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// The parts: EXR files written by `conetrace render --region/--samples/--part`.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The merged EXR.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
}

/// One part as read from its file.
struct Part {
    path: PathBuf,
    film: Film,
    /// Its pixels in the whole image.
    region: PixelRect,
    samples: Range<u32>,
    attributes: ExrAttributes,
}

fn refuse(path: &Path, problem: impl std::fmt::Display) -> CommandError {
    CommandError::bad_input(format!("{}: {problem}", path.display()))
}

fn read_part(path: &Path) -> Result<Part, CommandError> {
    let (film, attributes) =
        film::read_exr(path).map_err(|e| CommandError::bad_input(format!("merge: {e}")))?;
    if attributes.incomplete {
        return Err(refuse(
            path,
            "an interrupted render (conetrace.incomplete = 1)",
        ));
    }
    let samples_text = attributes.strings.get(SAMPLES_ATTRIBUTE).ok_or_else(|| {
        refuse(
            path,
            format!("not a conetrace part (no {SAMPLES_ATTRIBUTE})"),
        )
    })?;
    let spp_text = attributes
        .strings
        .get("conetrace.option.spp")
        .ok_or_else(|| refuse(path, "not a conetrace part (no conetrace.option.spp)"))?;
    let spp: u32 = spp_text.parse().map_err(|_| {
        refuse(
            path,
            format!("conetrace.option.spp {spp_text:?} is not a number"),
        )
    })?;
    let samples = film::partial::parse_sample_range(samples_text, spp)
        .map_err(|problem| refuse(path, format!("{SAMPLES_ATTRIBUTE}: {problem}")))?;
    let weight = attributes.strings.get(SAMPLE_WEIGHT_ATTRIBUTE);
    if weight.map(String::as_str) != Some(samples.len().to_string().as_str()) {
        return Err(refuse(
            path,
            format!(
                "{SAMPLE_WEIGHT_ATTRIBUTE} {weight:?} does not match the {} samples of {samples_text}",
                samples.len()
            ),
        ));
    }
    let window = attributes.window.unwrap_or(ImageWindow {
        x0: 0,
        y0: 0,
        full_width: film.width(),
        full_height: film.height(),
    });
    let region = window.rect(film.width(), film.height());
    let partial = samples != (0..spp);
    if partial && !film.has(Layer::SampleSum) {
        return Err(refuse(
            path,
            "holds a sample range but no exact sample sums (sum.* channels)",
        ));
    }
    Ok(Part {
        path: path.to_path_buf(),
        film,
        region,
        samples,
        attributes,
    })
}

fn signature(attributes: &ExrAttributes) -> BTreeMap<&str, &str> {
    attributes
        .strings
        .iter()
        .filter(|(k, _)| is_signature_attribute(k))
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect()
}

/// The first signature item where `b` differs from the part read from `a_path` with header
/// `a`.
fn signature_difference(a_path: &Path, a: &ExrAttributes, b: &Part) -> Option<String> {
    let (sa, sb) = (signature(a), signature(&b.attributes));
    let keys: std::collections::BTreeSet<&str> = sa.keys().chain(sb.keys()).copied().collect();
    for key in keys {
        let (va, vb) = (sa.get(key), sb.get(key));
        if va != vb {
            let show = |v: Option<&&str>| v.map_or("absent".to_string(), |v| v.to_string());
            return Some(format!(
                "not the same render as {}: {key} is {} there, {} here",
                a_path.display(),
                show(va),
                show(vb)
            ));
        }
    }
    None
}

/// A part's layers other than its exact sums: the layers of the whole render.
fn image_layers(film: &Film) -> Vec<Layer> {
    film.layers()
        .into_iter()
        .filter(|l| *l != Layer::SampleSum)
        .collect()
}

/// What is kept of a part once it has been added: enough to check the next ones against it.
struct AddedPart {
    path: PathBuf,
    region: PixelRect,
    samples: Range<u32>,
}

/// The merge in progress. Parts are read and added one at a time, so it holds the result,
/// the exact sums and one part, whatever the number of parts.
struct Merge {
    /// The first part's file and header: the signature every other part must match.
    first_path: PathBuf,
    first_attributes: ExrAttributes,
    width: u32,
    height: u32,
    spp: u32,
    whole_layers: Vec<Layer>,
    merged: Film,
    /// Per pixel, the exact sums of the sample-range parts added so far (allocated with the
    /// first such part) and whether any was added.
    sums: Vec<[i128; 3]>,
    summed: Vec<bool>,
    /// Per pixel, the samples the parts added so far hold.
    sample_counts: Vec<u64>,
    added: Vec<AddedPart>,
}

impl Merge {
    /// Starts from the first part's signature, size and layers.
    fn new(first: &Part) -> Result<Merge, CommandError> {
        let sig = signature(&first.attributes);
        let number = |key: &str| -> Result<u32, CommandError> {
            sig.get(key)
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| refuse(&first.path, format!("no usable {key} attribute")))
        };
        let (width, height, spp) = (
            number("conetrace.option.width")?,
            number("conetrace.option.height")?,
            number("conetrace.option.spp")?.max(1),
        );
        let whole_layers = image_layers(&first.film);
        let merged =
            Film::try_new(width, height, &whole_layers).map_err(CommandError::bad_input)?;
        let pixel_count = width as usize * height as usize;
        Ok(Merge {
            first_path: first.path.clone(),
            first_attributes: first.attributes.clone(),
            width,
            height,
            spp,
            whole_layers,
            merged,
            sums: Vec::new(),
            summed: vec![false; pixel_count],
            sample_counts: vec![0; pixel_count],
            added: Vec::new(),
        })
    }

    /// Refuses `part` when it is not of the same render or holds samples an added part holds.
    fn check(&self, part: &Part) -> Result<(), CommandError> {
        if let Some(problem) = signature_difference(&self.first_path, &self.first_attributes, part)
        {
            return Err(refuse(&part.path, problem));
        }
        let (width, height) = (self.width, self.height);
        let (full_width, full_height) = part
            .attributes
            .window
            .map_or((part.film.width(), part.film.height()), |w| {
                (w.full_width, w.full_height)
            });
        if (full_width, full_height) != (width, height) {
            return Err(refuse(
                &part.path,
                format!(
                    "its display window is {full_width}x{full_height}, the render {width}x{height}"
                ),
            ));
        }
        let layers = image_layers(&part.film);
        if layers != self.whole_layers {
            return Err(refuse(
                &part.path,
                format!(
                    "has layers {layers:?}, {} has {:?}",
                    self.first_path.display(),
                    self.whole_layers
                ),
            ));
        }
        // No two parts may hold the same sample of the same pixel.
        for a in &self.added {
            let samples_meet =
                a.samples.start < part.samples.end && part.samples.start < a.samples.end;
            if let (true, Some(o)) = (samples_meet, a.region.intersection(&part.region)) {
                return Err(refuse(
                    &part.path,
                    format!(
                        "overlaps {}: both hold samples of pixels {},{} to {},{} (sample ranges {} and {})",
                        a.path.display(),
                        o.x0,
                        o.y0,
                        o.x0 + o.width,
                        o.y0 + o.height,
                        format_sample_range(&a.samples),
                        format_sample_range(&part.samples)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Adds a checked part's pixels: final colour, alpha and AOVs from a part holding sample
    /// 0, exact sums from a part holding a sample range.
    fn add(&mut self, part: Part) -> Result<(), CommandError> {
        let (width, spp) = (self.width as usize, self.spp);
        let full = part.samples == (0..spp);
        let mut digits = [0.0f32; 3 * sample_sum::DIGITS];
        let mut values = [0.0f32; 6];
        for (x, y) in part.region.pixels() {
            let (px, py) = (x - part.region.x0, y - part.region.y0);
            let index = y as usize * width + x as usize;
            self.sample_counts[index] += part.samples.len() as u64;
            if full || part.samples.start == 0 {
                // Alpha and AOVs describe sample 0; with every sample, colour is final too.
                for layer in &self.whole_layers {
                    let n = layer.channel_count();
                    part.film.get(*layer, px, py, &mut values[..n]);
                    if *layer == Layer::Color && !full {
                        let mut kept = [0.0f32; 4];
                        self.merged.get(Layer::Color, x, y, &mut kept);
                        values[..3].copy_from_slice(&kept[..3]);
                    }
                    self.merged.set(*layer, x, y, &values[..n]);
                }
            }
            if !full {
                if self.sums.is_empty() {
                    self.sums = vec![[0; 3]; self.summed.len()];
                }
                part.film.get(Layer::SampleSum, px, py, &mut digits);
                for (c, sum) in self.sums[index].iter_mut().enumerate() {
                    let chunk: &[f32; sample_sum::DIGITS] = digits
                        [c * sample_sum::DIGITS..(c + 1) * sample_sum::DIGITS]
                        .try_into()
                        .expect("a channel's digits");
                    let value = sample_sum::decode(chunk).ok_or_else(|| {
                        refuse(&part.path, format!("damaged sample sum at pixel {x},{y}"))
                    })?;
                    // Each part's sum is below 2^127 / 2^32 per sample: see `sample_sum`.
                    *sum = sum.checked_add(value).ok_or_else(|| {
                        refuse(
                            &part.path,
                            format!("sample sum out of range at pixel {x},{y}"),
                        )
                    })?;
                }
                self.summed[index] = true;
            }
        }
        self.added.push(AddedPart {
            path: part.path,
            region: part.region,
            samples: part.samples,
        });
        Ok(())
    }

    /// The merged film and the header a single render of the same options writes, once every
    /// pixel has all its samples.
    fn finish(mut self) -> Result<(Film, ExrAttributes), CommandError> {
        let (width, spp) = (self.width, self.spp);
        // With no overlaps, a pixel has all its samples exactly when its parts' ranges add
        // up to spp.
        if let Some(index) = self.sample_counts.iter().position(|&n| n != u64::from(spp)) {
            let (x, y) = (index % width as usize, index / width as usize);
            return Err(CommandError::bad_input(format!(
                "merge: pixel {x},{y} has {} of its {spp} samples in the parts given (a region or \
                 sample range is missing)",
                self.sample_counts[index]
            )));
        }
        for (index, sum) in self.sums.iter().enumerate() {
            if !self.summed[index] {
                continue;
            }
            let (x, y) = (
                (index % width as usize) as u32,
                (index / width as usize) as u32,
            );
            let mut color = [0.0f32; 4];
            self.merged.get(Layer::Color, x, y, &mut color);
            for c in 0..3 {
                color[c] = sample_sum::mean_of_sum(sum[c], spp);
            }
            self.merged.set(Layer::Color, x, y, &color);
        }

        let tile_count = crate::render::work_tiles(width, self.height).len();
        let first = &self.first_attributes;
        let mut attributes = ExrAttributes {
            software: first.software.clone(),
            incomplete: false,
            finished_tiles: Some(tile_count as u32),
            world_to_camera: first.world_to_camera,
            world_to_ndc: first.world_to_ndc,
            window: None,
            ..ExrAttributes::default()
        };
        for (k, v) in signature(first) {
            attributes.strings.insert(k.to_string(), v.to_string());
        }
        attributes.strings.insert(
            TILES_DONE_ATTRIBUTE.to_string(),
            encode_tiles(&vec![true; tile_count]),
        );
        attributes.strings.insert(
            SAMPLES_ATTRIBUTE.to_string(),
            format_sample_range(&(0..spp)),
        );
        attributes
            .strings
            .insert(SAMPLE_WEIGHT_ATTRIBUTE.to_string(), spp.to_string());
        Ok((self.merged, attributes))
    }
}

/// The merged film and the header of the whole render, from checked parts. The parts are
/// read one at a time: the memory is the result's, the exact sums' and one part's.
pub fn merge_parts(paths: &[PathBuf]) -> Result<(Film, ExrAttributes), CommandError> {
    let mut merge: Option<Merge> = None;
    for path in paths {
        let part = read_part(path)?;
        let merge = match &mut merge {
            Some(merge) => merge,
            None => merge.insert(Merge::new(&part)?),
        };
        merge.check(&part)?;
        merge.add(part)?;
    }
    merge
        .ok_or_else(|| CommandError::bad_input("merge: no parts given"))?
        .finish()
}

pub fn run(args: &MergeArgs) -> Result<(), CommandError> {
    let output = &args.output;
    if !output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        return Err(refuse(output, "the merged image must be an .exr file"));
    }
    let same_file = |a: &Path, b: &Path| match (std::fs::canonicalize(a), std::fs::canonicalize(b))
    {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if let Some(part) = args.parts.iter().find(|p| same_file(p, output)) {
        return Err(refuse(
            output,
            format!("would overwrite the part {}", part.display()),
        ));
    }
    let (film, attributes) = merge_parts(&args.parts)?;
    let mut set = OutputSet::default();
    let written = |e: film::OutputError| CommandError::bad_input(e.to_string());
    film::stage_exr(&mut set, &film, output, &attributes).map_err(written)?;
    set.commit().map_err(written)?;
    println!(
        "merged {} parts into {} ({}x{})",
        args.parts.len(),
        output.display(),
        film.width(),
        film.height()
    );
    Ok(())
}
