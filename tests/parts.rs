//! Parts of an image (`--tile`, `--crop`, `--pixel-bounds`), `whitted merge`, streamed output.
//! The criteria: 4 tiles of `phong` at 1024x768 merged equal the full render exactly,
//! 3 of the 4 fail naming the missing range, a tile's EXR carries the right windows.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use whitted::image::PixelBounds;
use whitted::render::{Engine, Settings, Stage, render, render_part};

fn whitted() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_whitted"));
    c.env("WHITTED_ASSETS", common::assets());
    c
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("whitted-parts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn run(args: &[&str]) -> String {
    let r = whitted().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success(), "{args:?}: {stderr}");
    stderr
}

/// The exit code 2 and the one-line error of a command that must fail.
fn fails(args: &[&str]) -> String {
    let r = whitted().args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
    assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(
        stderr.trim().lines().count(),
        1,
        "{args:?}: one line: {stderr}"
    );
    stderr
}

/// An EXR read with the exr crate: display window, data window, RGB pixels of the data window.
struct Exr {
    display: (i32, i32, usize, usize),
    data: (i32, i32, usize, usize),
    pixels: Vec<[f32; 3]>,
}

fn read_exr(path: &Path) -> Exr {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.0, vec![[0f32; 3]; res.0 * res.1]),
        |(w, v): &mut (usize, Vec<[f32; 3]>), p, (r, g, b, _): (f32, f32, f32, f32)| {
            v[p.1 * *w + p.0] = [r, g, b]
        },
    )
    .unwrap();
    let d = img.attributes.display_window;
    let l = &img.layer_data;
    Exr {
        display: (d.position.0, d.position.1, d.size.0, d.size.1),
        data: (
            l.attributes.layer_position.0,
            l.attributes.layer_position.1,
            l.size.0,
            l.size.1,
        ),
        pixels: l.channel_data.pixels.1.clone(),
    }
}

fn bits(p: &[[f32; 3]]) -> Vec<[u32; 3]> {
    p.iter().map(|c| c.map(f32::to_bits)).collect()
}

#[test]
fn four_tiles_of_phong_merge_to_the_full_render_and_three_name_the_gap() {
    let full = tmp("phong-full.exr");
    let size = ["--width", "1024", "--height", "768"];
    let full_s = full.to_str().unwrap();
    run(&[&["render", "phong", "-q", "-o", full_s][..], &size].concat());
    let tiles: Vec<PathBuf> = (0..4).map(|i| tmp(&format!("phong-{i}.exr"))).collect();
    for (i, t) in tiles.iter().enumerate() {
        let tile = format!("{i}/4");
        let summary = run(&[
            &[
                "render",
                "phong",
                "--tile",
                &tile,
                "-o",
                t.to_str().unwrap(),
            ][..],
            &size,
        ]
        .concat());
        // the summary line describes the part
        let want = format!(
            "1024x192 part (x 0..1024, y {}..{}) of 1024x768 phong",
            192 * i,
            192 * (i + 1)
        );
        assert!(summary.contains(&want), "{summary}");
        // the tile's EXR: the whole image as display window, the band as data window
        let e = read_exr(t);
        assert_eq!(e.display, (0, 0, 1024, 768));
        assert_eq!(e.data, (0, 192 * i as i32, 1024, 192));
    }
    let t: Vec<&str> = tiles.iter().map(|t| t.to_str().unwrap()).collect();
    let merged = tmp("phong-merged.exr");
    run(&[
        "merge",
        t[0],
        t[1],
        t[2],
        t[3],
        "-o",
        merged.to_str().unwrap(),
    ]);
    let (a, b) = (read_exr(&full), read_exr(&merged));
    assert_eq!((a.display, a.data), (b.display, b.data));
    assert_eq!(bits(&a.pixels), bits(&b.pixels), "merged != full render");
    // same compression, same blocks: the very same bytes
    assert_eq!(
        std::fs::read(&full).unwrap(),
        std::fs::read(&merged).unwrap()
    );

    // parts given in any order merge the same
    let shuffled = tmp("phong-shuffled.exr");
    run(&[
        "merge",
        t[2],
        t[0],
        t[3],
        t[1],
        "-o",
        shuffled.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read(&full).unwrap(),
        std::fs::read(&shuffled).unwrap()
    );

    // three of four: the missing band is named, and nothing is written
    let out = tmp("phong-3of4.exr");
    let e = fails(&["merge", t[0], t[1], t[3], "-o", out.to_str().unwrap()]);
    assert!(e.contains("missing x 0..1024, y 384..576"), "{e}");
    assert!(!out.exists());
    // a part twice: the overlap is named
    let e = fails(&[
        "merge",
        t[0],
        t[1],
        t[1],
        t[2],
        t[3],
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("overlap at x 0..1024, y 192..384"), "{e}");

    // the merge to PNG is the full render's PNG, pixel for pixel
    let (full_png, merged_png) = (tmp("phong-full.png"), tmp("phong-merged.png"));
    run(&[
        &["render", "phong", "-q", "-o", full_png.to_str().unwrap()][..],
        &size,
    ]
    .concat());
    run(&[
        "merge",
        t[0],
        t[1],
        t[2],
        t[3],
        "-q",
        "-o",
        merged_png.to_str().unwrap(),
    ]);
    let (a, b) = (
        image::open(&full_png).unwrap(),
        image::open(&merged_png).unwrap(),
    );
    assert_eq!(a.to_rgb8(), b.to_rgb8());

    // `whitted info` shows both windows of a tile
    let r = whitted().args(["info", "--json", t[2]]).output().unwrap();
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(
        v["display_window"],
        serde_json::json!({"x": [0, 1024], "y": [0, 768]})
    );
    assert_eq!(
        v["data_window"],
        serde_json::json!({"x": [0, 1024], "y": [384, 576]})
    );
    assert_eq!(v["compression"], "piz");
}

/// Any part, cut anywhere (across tiles, one pixel wide, at the image's ragged edge), renders
/// exactly the full render's pixels, on every scene, both engines, with 1 and 4 spp.
#[test]
fn parts_equal_the_full_render_bit_for_bit() {
    let parts = [
        PixelBounds {
            x0: 0,
            x1: 70,
            y0: 0,
            y1: 45,
        },
        PixelBounds {
            x0: 13,
            x1: 14,
            y0: 0,
            y1: 45,
        },
        PixelBounds {
            x0: 5,
            x1: 61,
            y0: 17,
            y1: 18,
        },
        PixelBounds {
            x0: 31,
            x1: 70,
            y0: 29,
            y1: 45,
        },
        PixelBounds {
            x0: 16,
            x1: 48,
            y0: 16,
            y1: 32,
        },
    ];
    for scene in ["phong", "texture", "refraction", "vertex_color"] {
        let world = common::world(scene, 70, 45);
        for engine in [Engine::Auto, Engine::Packet, Engine::Scalar] {
            for spp in [1, 4] {
                let settings = Settings {
                    engine,
                    spp,
                    stage: None::<Stage>,
                    ..Settings::default()
                };
                let (full, _) = render(&world, &settings, &|_| {});
                for p in parts {
                    let (img, stats) = render_part(&world, &settings, p, &|_| {});
                    assert_eq!(
                        (img.width, img.height),
                        (p.width() as usize, p.height() as usize)
                    );
                    assert!(stats.over_budget_pixel(70).is_none());
                    for y in p.y0..p.y1 {
                        for x in p.x0..p.x1 {
                            let (a, b) = (
                                img.get((x - p.x0) as usize, (y - p.y0) as usize),
                                full.get(x as usize, y as usize),
                            );
                            assert_eq!(
                                a.to_array().map(f32::to_bits),
                                b.to_array().map(f32::to_bits),
                                "{scene} {engine:?} spp {spp} part {p} pixel ({x}, {y})"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// `--crop` (fractions) and `--pixel-bounds` parts as files: the EXR part holds the full
/// render's pixels in its data window; the PNG part holds just the part; crops merge with
/// tiles of another split as long as they cover the image once.
#[test]
fn crops_and_pixel_bounds_as_files_and_mixed_merges() {
    let size = ["--width", "160", "--height", "90"];
    let full = tmp("crop-full.exr");
    run(&[
        &["render", "phong", "-q", "-o", full.to_str().unwrap()][..],
        &size,
    ]
    .concat());
    let f = read_exr(&full);
    // x 0..80 (ceil(160 * 0.5)), y 0..30 (ceil(90 / 3) = 30)
    let left = tmp("crop-left.exr");
    run(&[
        &[
            "render",
            "phong",
            "-q",
            "--crop",
            "0,0.5,0,0.3333333",
            "-o",
            left.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    let right = tmp("crop-right.exr");
    run(&[
        &[
            "render",
            "phong",
            "-q",
            "--pixel-bounds",
            "80,160,0,30",
            "-o",
            right.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    let bottom = tmp("crop-bottom.exr");
    run(&[
        &[
            "render",
            "phong",
            "-q",
            "--crop",
            "0,1,0.3333333,1",
            "-o",
            bottom.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    let l = read_exr(&left);
    assert_eq!((l.display, l.data), ((0, 0, 160, 90), (0, 0, 80, 30)));
    let b = read_exr(&bottom);
    assert_eq!(b.data, (0, 30, 160, 60));
    for (y, row) in b.pixels.chunks(160).enumerate() {
        assert_eq!(bits(row), bits(&f.pixels[(30 + y) * 160..(31 + y) * 160]));
    }
    let merged = tmp("crop-merged.exr");
    let names = [&left, &right, &bottom].map(|p| p.to_str().unwrap().to_string());
    run(&[
        "merge",
        &names[0],
        &names[1],
        &names[2],
        "-q",
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(bits(&read_exr(&merged).pixels), bits(&f.pixels));
    // left and right without the bottom: the bottom band is missing
    let e = fails(&[
        "merge",
        &names[0],
        &names[1],
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert!(e.contains("missing x 0..160, y 30..90"), "{e}");
    // left and bottom: the top right is missing
    let e = fails(&[
        "merge",
        &names[0],
        &names[2],
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert!(e.contains("missing x 80..160, y 0..30"), "{e}");

    // the PNG part is just the part, and its pixels are the full PNG's
    let (full_png, part_png) = (tmp("crop-full.png"), tmp("crop-part.png"));
    run(&[
        &["render", "phong", "-q", "-o", full_png.to_str().unwrap()][..],
        &size,
    ]
    .concat());
    run(&[
        &[
            "render",
            "phong",
            "-q",
            "--pixel-bounds",
            "7,100,11,60",
            "-o",
            part_png.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    let (a, p) = (
        image::open(&full_png).unwrap().to_rgb8(),
        image::open(&part_png).unwrap().to_rgb8(),
    );
    assert_eq!(p.dimensions(), (93, 49));
    for (x, y, px) in p.enumerate_pixels() {
        assert_eq!(px, a.get_pixel(x + 7, y + 11));
    }
}

/// `--half` parts merge bit for bit into the `--half` full render (the merge keeps 16 bits),
/// and ZIPS / PIZ / RLE / uncompressed files hold the same pixels as the default ZIP.
#[test]
fn half_and_every_compression_hold_the_same_pixels() {
    let size = ["--width", "96", "--height", "64"];
    let full = tmp("half-full.exr");
    run(&[
        &[
            "render",
            "phong",
            "-q",
            "--half",
            "-o",
            full.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    let parts: Vec<String> = (0..3)
        .map(|i| {
            let p = tmp(&format!("half-{i}.exr")).to_str().unwrap().to_string();
            run(&[
                &[
                    "render",
                    "phong",
                    "-q",
                    "--half",
                    "--tile",
                    &format!("{i}/3"),
                    "-o",
                    &p,
                ][..],
                &size,
            ]
            .concat());
            p
        })
        .collect();
    let merged = tmp("half-merged.exr");
    run(&[
        "merge",
        &parts[0],
        &parts[1],
        &parts[2],
        "-q",
        "-o",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read(&full).unwrap(),
        std::fs::read(&merged).unwrap()
    );
    let r = whitted()
        .args(["info", "--json"])
        .arg(&merged)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["bits"], 16);

    let zip = tmp("c-default.exr");
    run(&[
        &["render", "phong", "-q", "-o", zip.to_str().unwrap()][..],
        &size,
    ]
    .concat());
    let want = bits(&read_exr(&zip).pixels);
    let h = read_exr(&full);
    let rounded: Vec<[f32; 3]> = read_exr(&zip)
        .pixels
        .iter()
        .map(|p| p.map(|c| exr::prelude::f16::from_f32(c).to_f32()))
        .collect();
    assert_eq!(bits(&h.pixels), bits(&rounded));
    for c in ["zip", "zips", "piz", "rle", "none"] {
        let p = tmp(&format!("c-{c}.exr"));
        run(&[
            &[
                "render",
                "phong",
                "-q",
                "--exr-compression",
                c,
                "-o",
                p.to_str().unwrap(),
            ][..],
            &size,
        ]
        .concat());
        assert_eq!(bits(&read_exr(&p).pixels), want, "{c}");
    }
}

#[test]
fn bad_parts_and_merges_are_one_line_errors() {
    let out = tmp("bad.exr");
    let o = out.to_str().unwrap();
    let size = ["--width", "64", "--height", "48"];
    for (args, want) in [
        (vec!["--tile", "4/4"], "--tile 4/4"),
        (vec!["--tile", "0/4x"], "--tile"),
        (vec!["--tile", "0/5"], "only 3 bands"),
        (vec!["--crop", "0,1,0"], "--crop"),
        (vec!["--crop", "0.5,0.2,0,1"], "x0 < x1"),
        (vec!["--pixel-bounds", "0,65,0,48"], "x0 < x1 <= 64"),
        (vec!["--exr-compression", "lzma"], "unknown EXR compression"),
    ] {
        let e = fails(&[&["render", "demo", "-o", o][..], &size, &args].concat());
        assert!(e.contains(want), "{args:?}: {e}");
    }
    // merge: a part of another image, a file that is no EXR, a missing file
    let (a, b) = (tmp("m-a.exr"), tmp("m-b.exr"));
    run(&[
        &[
            "render",
            "demo",
            "-q",
            "--tile",
            "0/2",
            "-o",
            a.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat());
    run(&[
        "render",
        "demo",
        "-q",
        "--width",
        "32",
        "--height",
        "48",
        "--tile",
        "1/2",
        "-o",
        b.to_str().unwrap(),
    ]);
    let e = fails(&["merge", a.to_str().unwrap(), b.to_str().unwrap(), "-o", o]);
    assert!(
        e.contains("display window") && e.contains("different images"),
        "{e}"
    );
    let e = fails(&["merge", a.to_str().unwrap(), "Cargo.toml", "-o", o]);
    assert!(
        e.contains("Cargo.toml") && e.contains("cannot read EXR"),
        "{e}"
    );
    let e = fails(&["merge", "no-such-part.exr", "-o", o]);
    assert!(e.contains("no-such-part.exr"), "{e}");
    assert!(!out.exists());
}

/// A render that fails leaves the image that was at its output path, and no temporary file:
/// the trapped-rays scene fails after its first band of tiles.
#[test]
fn a_failed_render_leaves_the_old_image_and_no_temporary_file() {
    let dir = tmp("atomic");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("trap.toml");
    std::fs::write(&scene, common::TRAP).unwrap();
    for ext in ["exr", "png"] {
        let out = dir.join(format!("keep.{ext}"));
        run(&[
            "render",
            "demo",
            "-q",
            "--width",
            "32",
            "--height",
            "24",
            "-o",
            out.to_str().unwrap(),
        ]);
        let good = std::fs::read(&out).unwrap();
        let e = fails(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(e.contains("rays are trapped"), "{e}");
        assert_eq!(std::fs::read(&out).unwrap(), good);
    }
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["keep.exr", "keep.png", "trap.toml"]);
}

/// `--subdivide` is checked against the scene's triangle cap before any mesh is subdivided:
/// level 6 of the kitten (84M triangles) is refused at once.
#[test]
fn subdivision_past_the_triangle_cap_is_refused_before_subdividing() {
    let out = tmp("sub6.png");
    let e = fails(&[
        "render",
        "phong",
        "--subdivide",
        "6",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        e.contains("--subdivide 6 would make 83722240 triangles from 20440"),
        "{e}"
    );
    assert!(!out.exists());
}

/// The peak memory of `/usr/bin/time -v` (maximum resident set) of a whitted command, in MB.
fn peak_mb(args: &[&str]) -> f64 {
    let r = Command::new("/usr/bin/time")
        .arg("-v")
        .arg(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .env("WHITTED_ASSETS", common::assets())
        .output()
        .expect("/usr/bin/time (Debian package `time`)");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{args:?}: {stderr}");
    let kb: f64 = stderr
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("Maximum resident set size (kbytes): ")
        })
        .expect("maximum resident set size")
        .parse()
        .unwrap();
    kb / 1e3
}

/// Streaming output: a 16384x8192 `phong` EXR peaks under 600 MB (its f32 frame buffer alone
/// would be 1.6 GB); about 2 minutes on 2 cores:
/// `cargo test --release --test parts -- --ignored --nocapture sixteen_k`.
#[test]
#[ignore]
fn sixteen_k_phong_exr_peaks_under_600_mb() {
    let out = tmp("phong-16k.exr");
    let o = out.to_str().unwrap();
    let mb = peak_mb(&[
        "render", "phong", "--width", "16384", "--height", "8192", "-q", "-o", o,
    ]);
    println!("16384x8192 phong EXR: peak {mb:.0} MB");
    assert!(mb < 600.0, "peak {mb:.0} MB");
    let _ = std::fs::remove_file(&out);
}

/// 5.2M triangles render: `phong --subdivide 4` (about 2 GB and 10-20 s):
/// `cargo test --release --test parts -- --ignored --nocapture subdivide_4`.
#[test]
#[ignore]
fn subdivide_4_renders_five_million_triangles() {
    let out = tmp("phong-sub4.png");
    let r = whitted()
        .args([
            "render",
            "phong",
            "--subdivide",
            "4",
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(stderr.contains("5232640 triangles"), "{stderr}");
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (1024, 768));
}
