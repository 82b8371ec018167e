//! Fuzz OBJ and glTF loading through to a committed Embree scene: the first input byte picks
//! the format (OBJ, glTF JSON or binary glTF), the rest is the file.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, body)) = data.split_first() else {
        return;
    };
    let name = match selector % 3 {
        0 => "model.obj",
        1 => "model.gltf",
        _ => "model.glb",
    };
    let path = common::scratch_dir().join(name);
    if std::fs::write(&path, body).is_err() {
        return;
    }
    common::load_prepare_render(&path);
});
