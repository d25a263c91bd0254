//! Writing a render with AOV layers: one EXR whose channels are named the way tev and
//! OpenImageIO group them into layers (`R G B` for the beauty image, then `albedo.R`,
//! `normal.X`, `depth.Z`, `id.id`...). Kept apart from the plain image writer.

use crate::aov::AovImages;
use crate::error::Result;
use crate::image::Image;
use std::path::Path;

/// The channel names of each AOV layer (layer `.` channel).
pub const CHANNELS: [(&str, &[&str]); 4] = [
    ("albedo", &["albedo.R", "albedo.G", "albedo.B"]),
    ("normal", &["normal.X", "normal.Y", "normal.Z"]),
    ("depth", &["depth.Z"]),
    ("id", &["id.id"]),
];

/// Write `beauty` (linear f32 RGB) and the captured layers into one EXR at `path`, through a
/// temporary file renamed into place, so a failed write leaves no truncated file.
pub fn save_exr_with_aovs(beauty: &Image, aovs: &AovImages, path: &Path) -> Result<()> {
    use exr::prelude::*;
    assert_eq!((beauty.width, beauty.height), (aovs.width, aovs.height));
    let f32s =
        |f: &dyn Fn(usize) -> f32| FlatSamples::F32((0..beauty.pixels.len()).map(f).collect());
    let mut list = vec![
        AnyChannel::new("R", f32s(&|i| beauty.pixels[i].x)),
        AnyChannel::new("G", f32s(&|i| beauty.pixels[i].y)),
        AnyChannel::new("B", f32s(&|i| beauty.pixels[i].z)),
    ];
    for (v, names) in [(&aovs.albedo, CHANNELS[0].1), (&aovs.normal, CHANNELS[1].1)] {
        if let Some(v) = v {
            for (a, name) in names.iter().enumerate() {
                list.push(AnyChannel::new(*name, f32s(&|i| v[i][a])));
            }
        }
    }
    if let Some(d) = &aovs.depth {
        list.push(AnyChannel::new(CHANNELS[2].1[0], f32s(&|i| d[i])));
    }
    if let Some(id) = &aovs.id {
        list.push(AnyChannel::new(
            CHANNELS[3].1[0],
            FlatSamples::U32(id.clone()),
        ));
    }
    let channels = AnyChannels::sort(list.into());
    let image = exr::image::Image::from_channels((beauty.width, beauty.height), channels);
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}",
        path.file_name()
            .map_or("out".into(), |n| n.to_string_lossy()),
        std::process::id()
    ));
    let result = image
        .write()
        .to_file(&tmp)
        .map_err(|e| crate::Error::image(path, format!("cannot write EXR: {e}")))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| crate::Error::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
