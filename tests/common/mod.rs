//! Helpers shared by the whole-program tests: run the binary, write scene files, read EXRs.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The conetrace binary built for these tests.
pub fn conetrace() -> Command {
    Command::new(env!("CARGO_BIN_EXE_conetrace"))
}

/// Run conetrace with `args` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    conetrace()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the conetrace binary runs")
}

/// A fresh temporary directory for one test.
pub fn temp_dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("temporary directory")
}

/// Write `text` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test file");
    path
}

/// An OBJ square in the plane y = `y`, from -half to +half in x and z, facing +y, with uvs.
pub fn square_obj(half: f32, y: f32) -> String {
    format!(
        "v {n} {y} {n}\nv {p} {y} {n}\nv {p} {y} {p}\nv {n} {y} {p}\n\
         vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nvn 0 1 0\n\
         f 1/1/1 4/4/1 3/3/1\nf 1/1/1 3/3/1 2/2/1\n",
        n = -half,
        p = half,
        y = y
    )
}

/// An image read back from an EXR: width, height and named channels.
pub struct ExrImage {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    pub fn channel(&self, name: &str) -> &[f32] {
        &self
            .channels
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("channel {name} missing; have {:?}", self.names()))
            .1
    }
    pub fn names(&self) -> Vec<String> {
        self.channels.iter().map(|(n, _)| n.clone()).collect()
    }
    pub fn at(&self, name: &str, x: usize, y: usize) -> f32 {
        self.channel(name)[y * self.width + x]
    }
}

/// Read every channel of the first layer group of an EXR as f32.
pub fn read_exr(path: &Path) -> ExrImage {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("read {}: {e}", path.display()));
    let mut channels = Vec::new();
    let mut size = (0, 0);
    for layer in &image.layer_data {
        size = (layer.size.width(), layer.size.height());
        let prefix = layer
            .attributes
            .layer_name
            .as_ref()
            .map(|n| format!("{n}."))
            .unwrap_or_default();
        for channel in &layer.channel_data.list {
            let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
            channels.push((format!("{prefix}{}", channel.name), values));
        }
    }
    ExrImage {
        width: size.0,
        height: size.1,
        channels,
    }
}
