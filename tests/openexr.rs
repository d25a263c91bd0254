//! Every EXR compression whitted writes, read back by OpenEXR itself (its Python bindings,
//! `pip install OpenEXR`, which `.ci/run` installs): each channel's samples, bit for bit, are
//! those the `exr` crate reads, and the same under every compression; for f32 and `--half`,
//! beauty and AOV layers, whole images and parts. Without the bindings the test fails when
//! `CI=true` and is skipped (saying so) otherwise.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("whitted-openexr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn render(args: &[&str], out: &Path) {
    let r = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .env("WHITTED_ASSETS", common::assets())
        .args(["render", "phong", "-q", "--width", "101", "--height", "67"])
        .args(args)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        r.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&r.stderr)
    );
}

/// Channel name -> little-endian sample bytes, as the `exr` crate reads them; and the data
/// window's corner.
fn read_with_exr_crate(path: &Path) -> (BTreeMap<String, Vec<u8>>, (i32, i32)) {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let pos = img.layer_data.attributes.layer_position;
    let channels = img
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            let bytes = match &c.sample_data {
                FlatSamples::F16(v) => v.iter().flat_map(|s| s.to_le_bytes()).collect(),
                FlatSamples::F32(v) => v.iter().flat_map(|s| s.to_le_bytes()).collect(),
                FlatSamples::U32(v) => v.iter().flat_map(|s| s.to_le_bytes()).collect(),
            };
            (c.name.to_string(), bytes)
        })
        .collect();
    (channels, (pos.0, pos.1))
}

/// What OpenEXR reads from each file: `dir/K.CHANNEL.bin` (the samples' bytes) for the K-th
/// file, and the data windows' corners; None when the bindings are not installed.
const READER: &str = r#"
import sys, OpenEXR
out = sys.argv[1]
for k, path in enumerate(sys.argv[2:]):
    with OpenEXR.File(path, separate_channels=True) as f:
        (x0, y0), _ = f.header()["dataWindow"]
        print(k, int(x0), int(y0), str(f.header()["compression"]))
        for name, ch in f.channels().items():
            open(f"{out}/{k}.{name}.bin", "wb").write(ch.pixels.astype(ch.pixels.dtype.newbyteorder("<")).tobytes())
"#;

fn openexr_available() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import OpenEXR"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but OpenEXR's Python bindings are missing (python3 -c 'import OpenEXR' fails): \
             .ci/run installs them with pip install OpenEXR"
        );
        eprintln!("SKIPPED: OpenEXR's Python bindings are not installed (pip install OpenEXR)");
    }
    ok
}

#[test]
fn openexr_reads_every_compression_bit_for_bit() {
    if !openexr_available() {
        return;
    }
    let codecs = ["zip", "zips", "piz", "rle", "none"];
    // (options, expected data window corner): whole images, a crop whose blocks are cut at
    // odd rows, a tile, AOV layers, 16-bit floats
    let aovs = ["--aov", "albedo,normal,depth,id"];
    let cases: Vec<(Vec<&str>, (i32, i32))> = vec![
        (vec![], (0, 0)),
        (vec!["--half"], (0, 0)),
        (vec!["--crop", "0.13,0.91,0.07,0.95"], (14, 5)),
        (vec!["--tile", "1/3"], (0, 16)),
        (aovs.to_vec(), (0, 0)),
        (
            [&aovs[..], &["--half", "--crop", "0.1,0.6,0.3,0.9"]].concat(),
            (11, 21),
        ),
    ];
    let mut files = Vec::new();
    for (case, (opts, _)) in cases.iter().enumerate() {
        for c in codecs {
            let path = tmp(&format!("{case}-{c}.exr"));
            render(&[&opts[..], &["--exr-compression", c]].concat(), &path);
            files.push((case, c, path));
        }
    }
    let dir = tmp("openexr");
    std::fs::create_dir_all(&dir).unwrap();
    let r = Command::new("python3")
        .args(["-c", READER])
        .arg(&dir)
        .args(files.iter().map(|f| &f.2))
        .output()
        .unwrap();
    assert!(
        r.status.success(),
        "OpenEXR failed: {}",
        String::from_utf8_lossy(&r.stderr)
    );
    let report = String::from_utf8(r.stdout).unwrap();
    let lines: Vec<&str> = report.lines().collect();
    assert_eq!(lines.len(), files.len(), "{report}");
    let mut by_case: BTreeMap<usize, BTreeMap<String, Vec<u8>>> = BTreeMap::new();
    for (k, (case, codec, path)) in files.iter().enumerate() {
        let (ours, corner) = read_with_exr_crate(path);
        assert_eq!(corner, cases[*case].1, "{codec} {:?}", cases[*case].0);
        let f: Vec<&str> = lines[k].split(' ').collect();
        assert_eq!(
            f[1..3],
            [corner.0.to_string(), corner.1.to_string()],
            "{}",
            lines[k]
        );
        let name = if *codec == "none" { "no" } else { codec };
        assert!(
            f[3].to_ascii_lowercase()
                .contains(&format!("{name}_compression")),
            "{codec}: {}",
            lines[k]
        );
        for (channel, bytes) in &ours {
            let theirs = std::fs::read(dir.join(format!("{k}.{channel}.bin"))).unwrap();
            assert!(
                theirs == *bytes,
                "{codec} {:?} channel {channel}: OpenEXR reads other samples",
                cases[*case].0
            );
        }
        let n = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                let e = e.as_ref().unwrap().file_name();
                e.to_string_lossy().starts_with(&format!("{k}."))
            })
            .count();
        assert_eq!(n, ours.len(), "{codec}: the channels OpenEXR sees");
        // the same samples under every compression
        match by_case.get(case) {
            None => {
                by_case.insert(*case, ours);
            }
            Some(first) => assert!(*first == ours, "{codec} {:?}", cases[*case].0),
        }
    }
    let aov_channels: Vec<&String> = by_case[&4].keys().collect();
    assert_eq!(
        aov_channels,
        [
            "B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z", "id.id", "normal.X",
            "normal.Y", "normal.Z"
        ]
    );
}
