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
    // through the writer every output uses (a temporary file renamed into place)
    crate::io::output::write_atomically(path, |out| {
        image
            .write()
            .to_buffered(out)
            .map_err(|e| crate::Error::image(path, format!("cannot write EXR: {e}")))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The layers come back from the file as written, and a failed write (the target is a
    /// folder) leaves no temporary file.
    #[test]
    fn layers_read_back_as_written() {
        let d = std::env::temp_dir().join(format!("whitted-aov-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let (w, h) = (5, 3);
        let px: Vec<Vec3> = (0..w * h).map(|i| Vec3::new(i as f32, 0.5, -1.0)).collect();
        let beauty = crate::image::Image {
            width: w,
            height: h,
            pixels: px.clone(),
        };
        let aovs = AovImages {
            width: w,
            height: h,
            albedo: None,
            normal: Some(px.iter().map(|p| Vec3::new(p.y, p.z, p.x)).collect()),
            depth: Some((0..w * h).map(|i| i as f32 * 0.25).collect()),
            id: Some((0..(w * h) as u32).collect()),
        };
        let path = d.join("layers.exr");
        save_exr_with_aovs(&beauty, &aovs, &path).unwrap();
        use exr::prelude::*;
        let image = read_all_flat_layers_from_file(&path).unwrap();
        let channels = &image.layer_data[0].channel_data.list;
        let named = |n: &str| {
            channels
                .iter()
                .find(|c| c.name == *n)
                .unwrap_or_else(|| panic!("channel {n}"))
        };
        let f32s = |n: &str| named(n).sample_data.values_as_f32().collect::<Vec<f32>>();
        assert_eq!(f32s("R"), px.iter().map(|p| p.x).collect::<Vec<_>>());
        assert_eq!(f32s("normal.X"), px.iter().map(|p| p.y).collect::<Vec<_>>());
        assert_eq!(f32s("depth.Z")[7], 1.75);
        match &named("id.id").sample_data {
            FlatSamples::U32(ids) => assert_eq!(ids, &(0..(w * h) as u32).collect::<Vec<_>>()),
            other => panic!("id as {other:?}"),
        }
        assert!(save_exr_with_aovs(&beauty, &aovs, &d).is_err());
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["layers.exr"]);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
