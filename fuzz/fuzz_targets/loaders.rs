//! Malformed files for every loader: image, TIFF stack, NIfTI, surfaces.
//! Loaders must return an error, never panic or hang.
#![no_main]

use dsc_seg::io::surface::{parse_surface, SurfaceFormat};
use dsc_seg::io::{Image2, Volume};
use libfuzzer_sys::fuzz_target;
use std::io::Write;

const EXTENSIONS: [&str; 6] = ["png", "tif", "nii", "nii.gz", "jpg", "bmp"];

fuzz_target!(|data: &[u8]| {
    let Some((&selector, bytes)) = data.split_first() else { return };
    let ext = EXTENSIONS[selector as usize % EXTENSIONS.len()];
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = dir.path().join(format!("input.{ext}"));
    std::fs::File::create(&path)
        .and_then(|mut f| f.write_all(bytes))
        .expect("write input");
    match ext {
        "png" | "jpg" | "bmp" => {
            let _ = Image2::load(&path);
        }
        _ => {
            let _ = Volume::load(&path);
        }
    }
    for format in [SurfaceFormat::Off, SurfaceFormat::Obj, SurfaceFormat::Stl] {
        let _ = parse_surface(bytes, format);
    }
});
