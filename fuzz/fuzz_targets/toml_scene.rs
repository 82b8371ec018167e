//! Fuzz the TOML scene parser and validator: any bytes, parsed as a scene file and, when
//! accepted, prepared (Embree scene committed) and rendered at 4x4.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let path = common::scratch_dir().join("scene.toml");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    common::load_prepare_render(&path);
});
