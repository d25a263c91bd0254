//! Writes a scene file of an `n x n` field of kittens, each an `[[instance]]` of one mesh
//! (`meshes/kitten.m`), turned and scaled a little at random, on a floor,
//! seen from above one corner. The scale test of instancing (README, "Instances"):
//!
//!     cargo run --release --example kitten_field -- 100 field.toml
//!     /usr/bin/time -v whitted render field.toml --width 1920 --height 1080 -o field.png

use std::fmt::Write;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(n), Some(out)) = (args.get(1).and_then(|n| n.parse::<u32>().ok()), args.get(2))
    else {
        eprintln!("usage: kitten_field N OUT.toml  (an N x N field of kittens)");
        std::process::exit(2);
    };
    let kitten = std::path::absolute(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/kitten.m"),
    )
    .unwrap();
    // the kitten is about 2 units across: 3 apart, the field centred on the origin
    let half = 1.5 * n as f32;
    let mut s = String::new();
    write!(
        s,
        r#"[image]
width = 1920
height = 1080
[camera]
eye = [{e}, {h}, {e}]
look_at = [0, -1, 0]
vfov = 50
[render]
depth = 2
[[light]]
position = [{l}, {h2}, {l3}]
intensity = [0.9, 0.9, 0.85]
[[light]]
position = [{nl}, {h2}, {l}]
intensity = [0.35, 0.35, 0.45]
[[material]]
name = "fur"
color = [0.95, 0.6, 0.3]
ks = 0.3
n = 40
[[material]]
name = "floor"
color = [0.5, 0.55, 0.6]
ks = 0.2
n = 10
[[mesh]]
name = "kitten"
file = "{kitten}"
material = "fur"
[[mesh]]
shape = "quad"
center = [0, -1.1, 0]
size = [{floor}, 1, {floor}]
material = "floor"
"#,
        e = half * 1.1,
        h = half * 0.6 + 2.0,
        h2 = half + 5.0,
        l = half * 0.8,
        l3 = half * 0.3,
        nl = -half * 0.8,
        floor = 2.0 * half + 4.0,
        kitten = kitten.display().to_string().replace('\\', "/"),
    )
    .unwrap();
    // xorshift: the same field every time
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    for i in 0..n {
        for j in 0..n {
            let x = 3.0 * i as f32 - half + 1.5;
            let z = 3.0 * j as f32 - half + 1.5;
            writeln!(
                s,
                "[[instance]]\nmesh = \"kitten\"\ntranslate = [{x}, 0, {z}]\nrotate = [0, {:.1}, 0]\nscale = {:.3}",
                360.0 * rnd(),
                0.8 + 0.4 * rnd()
            )
            .unwrap();
        }
    }
    std::fs::write(out, s).unwrap();
    eprintln!("{out}: {} kittens", n * n);
}
