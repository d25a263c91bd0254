use super::*;
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("whitted-out-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn listing(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A write that fails midway (after real bytes went out) leaves the old image as it was
/// and no temporary file; one that succeeds replaces it and leaves nothing else either.
#[test]
fn failed_writes_leave_the_old_file_and_no_temporary() {
    for (ext, compression) in [
        ("exr", ExrCompression::Piz),
        ("exr", ExrCompression::Zip),
        ("exr", ExrCompression::Zips),
        ("exr", ExrCompression::Rle),
        ("exr", ExrCompression::None),
        ("png", ExrCompression::Piz),
    ] {
        let opts = ExrOptions {
            compression,
            half: false,
        };
        let d = dir(&format!("atomic-{ext}-{compression:?}"));
        let path = d.join(format!("render.{ext}"));
        std::fs::write(&path, b"the good image").unwrap();
        let part = PixelBounds::full(64, 48);
        let row = vec![Vec3::splat(0.5); 64 * 16];
        let mut fail_after_one_band = |sink: &mut RowSink| -> Result<()> {
            sink(0, &row)?;
            Err(Error::Usage("the render failed midway".into()))
        };
        let r = write_streamed(&path, (64, 48), part, opts, &mut fail_after_one_band);
        assert!(r.unwrap_err().to_string().contains("failed midway"));
        assert_eq!(std::fs::read(&path).unwrap(), b"the good image");
        assert_eq!(listing(&d), [format!("render.{ext}")]);

        // too few rows is an error too, not a short image
        let r = write_streamed(&path, (64, 48), part, opts, &mut |s| s(0, &row));
        assert!(
            r.unwrap_err()
                .to_string()
                .contains("16 of the part's 48 rows")
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"the good image");
        assert_eq!(listing(&d), [format!("render.{ext}")]);

        write_streamed(&path, (64, 48), part, opts, &mut |s| {
            (0..3).try_for_each(|b| s(b * 16, &row))
        })
        .unwrap();
        assert_ne!(std::fs::read(&path).unwrap(), b"the good image");
        assert_eq!(listing(&d), [format!("render.{ext}")]);
    }
}

#[test]
fn an_unwritable_target_is_one_error_naming_it() {
    let d = dir("unwritable");
    let missing = d.join("no/such/folder/x.exr");
    let e = write_streamed(
        &missing,
        (8, 8),
        PixelBounds::full(8, 8),
        ExrOptions::default(),
        &mut |s| s(0, &[Vec3::ZERO; 64]),
    )
    .unwrap_err();
    assert!(e.to_string().contains("no/such/folder/x.exr"), "{e}");
    let e = write_streamed(
        &d,
        (8, 8),
        PixelBounds::full(8, 8),
        ExrOptions::default(),
        &mut |s| s(0, &[Vec3::ZERO; 64]),
    );
    assert!(e.is_err());
}

/// Rows given in any batch sizes make the same file, whatever the compression's block
/// height, and read back as written (f32 exactly; f16 to its rounding).
#[test]
fn exr_rows_in_any_batches_read_back_exactly() {
    let d = dir("batches");
    let (w, h) = (37u32, 45u32);
    let part = PixelBounds {
        x0: 3,
        x1: 40,
        y0: 5,
        y1: 50,
    };
    let px = |x: u32, y: u32| Vec3::new(x as f32 * 0.1, y as f32 * 1e-3, -(x as f32 + y as f32));
    let rows: Vec<Vec3> = (part.y0..part.y1)
        .flat_map(|y| (part.x0..part.x1).map(move |x| px(x, y)))
        .collect();
    for compression in ExrCompression::NAMES.map(|n| ExrCompression::from_name(n).unwrap()) {
        for half in [false, true] {
            let opts = ExrOptions { compression, half };
            let mut files = Vec::new();
            for batch in [1usize, 7, 16, 45] {
                let path = d.join(format!("{compression:?}-{half}-{batch}.exr"));
                write_streamed(&path, (w + 10, h + 10), part, opts, &mut |s| {
                    for (k, c) in rows.chunks(batch * w as usize).enumerate() {
                        s(part.y0 + (k * batch) as u32, c)?;
                    }
                    Ok(())
                })
                .unwrap();
                files.push(std::fs::read(&path).unwrap());
            }
            assert!(files.windows(2).all(|f| f[0] == f[1]), "{compression:?}");
            let path = d.join(format!("{compression:?}-{half}-1.exr"));
            let img = exr::prelude::read_first_rgba_layer_from_file(
                &path,
                |res, _| vec![Vec3::ZERO; res.0 * res.1],
                |v: &mut Vec<Vec3>, p, (r, g, b, _): (f32, f32, f32, f32)| {
                    v[p.1 * 37 + p.0] = Vec3::new(r, g, b)
                },
            )
            .unwrap();
            let layer = &img.layer_data;
            assert_eq!(layer.attributes.layer_position.0, 3);
            assert_eq!(layer.attributes.layer_position.1, 5);
            assert_eq!(layer.size.0, 37);
            assert_eq!(img.attributes.display_window.size.0, 47);
            let round = |v: Vec3| {
                if half {
                    Vec3::from(v.to_array().map(|c| f16::from_f32(c).to_f32()))
                } else {
                    v
                }
            };
            let want: Vec<Vec3> = rows.iter().copied().map(round).collect();
            assert_eq!(layer.channel_data.pixels, want, "{compression:?} {half}");
        }
    }
}

/// A block that deflate cannot shrink is stored raw (the size readers take for
/// uncompressed), one that it can is smaller; both read back bit for bit.
#[test]
fn zip_blocks_that_do_not_shrink_are_stored_raw() {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut noise = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        f32::from_bits((x as u32 & 0x807F_FFFF) | 0x3F00_0000) // finite, in +-[0.5, 1)
    };
    // random bytes: deflate adds its headers, so the block is stored raw
    let noisy: Vec<u8> = (0..4096).map(|_| noise().to_bits() as u8).collect();
    assert_eq!(zip_block(&noisy), noisy);
    let flat = vec![7u8; 4096];
    assert!(zip_block(&flat).len() < 100);

    let d = dir("zip-raw");
    let (w, h) = (64u32, 40u32);
    for pixels in [
        (0..w * h)
            .map(|_| Vec3::new(noise(), noise(), noise()))
            .collect::<Vec<_>>(),
        vec![Vec3::new(0.1, 0.12, 0.16); (w * h) as usize],
    ] {
        for compression in [ExrCompression::Zip, ExrCompression::Zips] {
            let path = d.join(format!("{compression:?}.exr"));
            let opts = ExrOptions {
                compression,
                half: false,
            };
            let part = PixelBounds::full(w, h);
            write_streamed(&path, (w, h), part, opts, &mut |s| s(0, &pixels)).unwrap();
            let img = exr::prelude::read_first_rgba_layer_from_file(
                &path,
                |res, _| vec![Vec3::ZERO; res.0 * res.1],
                |v: &mut Vec<Vec3>, p, (r, g, b, _): (f32, f32, f32, f32)| {
                    v[p.1 * 64 + p.0] = Vec3::new(r, g, b)
                },
            )
            .unwrap();
            assert_eq!(
                img.layer_data.channel_data.pixels, pixels,
                "{compression:?}"
            );
        }
    }
}

/// A symbolic link's file is replaced and the link stays a link (relative and dangling links
/// too); no temporary file is left.
#[cfg(unix)]
#[test]
fn writes_go_through_symbolic_links() {
    use std::os::unix::fs::symlink;
    let d = dir("links");
    std::fs::write(d.join("real.png"), b"old").unwrap();
    symlink("real.png", d.join("link.png")).unwrap();
    symlink(d.join("later.png"), d.join("dangling.png")).unwrap();
    for (link, file) in [("link.png", "real.png"), ("dangling.png", "later.png")] {
        write_atomically(&d.join(link), |out| {
            out.write_all(b"new").map_err(|e| Error::io(&d, e))
        })
        .unwrap();
        let meta = std::fs::symlink_metadata(d.join(link)).unwrap();
        assert!(meta.file_type().is_symlink(), "{link} is no longer a link");
        assert_eq!(std::fs::read(d.join(file)).unwrap(), b"new");
    }
    assert_eq!(
        listing(&d),
        ["dangling.png", "later.png", "link.png", "real.png"]
    );
}

/// A FIFO (or a device such as `/dev/stdout`) is written into, not replaced by a rename.
#[cfg(unix)]
#[test]
fn a_fifo_is_written_into() {
    let d = dir("fifo");
    let pipe = d.join("hits.bin");
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo did not run: skipped");
        return;
    }
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || std::fs::read(pipe).unwrap())
    };
    write_atomically(&pipe, |out| {
        out.write_all(b"through the pipe")
            .map_err(|e| Error::io(&pipe, e))
    })
    .unwrap();
    assert_eq!(reader.join().unwrap(), b"through the pipe");
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(&pipe)
            .unwrap()
            .file_type()
            .is_fifo()
    );
    assert_eq!(listing(&d), ["hits.bin"]);
}

/// A file replaced keeps its permissions.
#[cfg(unix)]
#[test]
fn a_replaced_file_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let d = dir("mode");
    let f = d.join("img.png");
    std::fs::write(&f, b"old").unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o640)).unwrap();
    write_atomically(&f, |out| {
        out.write_all(b"new").map_err(|e| Error::io(&f, e))
    })
    .unwrap();
    assert_eq!(std::fs::read(&f).unwrap(), b"new");
    assert_eq!(
        std::fs::metadata(&f).unwrap().permissions().mode() & 0o777,
        0o640
    );
}
