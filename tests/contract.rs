//! Renders of every canonical scene and stage, checked for what SCENES.md says must hold.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{settings, world};
use glam::Vec3;
use whitted::accel::intersect1;
use whitted::image::Image;
use whitted::render::{Stage, World, render};

const W: u64 = 96;
const H: u64 = 72;

fn draw(w: &World, stage: Option<Stage>) -> Image {
    render(w, &settings(stage), &|_| {}).0
}

/// Primary-hit object per pixel (`None` = background).
fn objects(w: &World) -> Vec<Option<u32>> {
    let cam = w.scene.camera();
    (0..w.scene.height)
        .flat_map(|j| (0..w.scene.width).map(move |i| (i, j)))
        .map(|(i, j)| {
            intersect1(&w.accel, &cam.primary_ray(i, j), w.scene.cull_backfaces)
                .map(|h| w.geometry.tri_object[h.tri as usize])
        })
        .collect()
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

#[test]
fn background_in_corners_and_kitten_in_centre_for_every_scene() {
    for name in ["phong", "vertex_color", "texture", "cubemap", "refraction"] {
        let w = world(name, W, H);
        let cam = w.scene.camera();
        let img = draw(&w, Some(Stage::Intersection));
        let (cx, cy) = (W as usize / 2, H as usize / 2);
        assert_eq!(img.get(cx, cy), Vec3::ONE, "{name}: kitten in the centre");
        for (x, y) in [(0, 0), (W as usize - 1, 0)] {
            let bg = w
                .scene
                .background
                .sample(cam.primary_ray(x as u32, y as u32).dir);
            assert_eq!(img.get(x, y), bg, "{name}: background at corner ({x}, {y})");
        }
        // Only white and background in the intersection stage.
        let hits = objects(&w);
        for (k, p) in img.pixels.iter().enumerate() {
            assert_eq!(*p == Vec3::ONE, hits[k].is_some(), "{name}: pixel {k}");
        }
    }
}

#[test]
fn every_scene_and_stage_renders_finite() {
    for name in ["phong", "vertex_color", "texture", "cubemap", "refraction"] {
        let w = world(name, 32, 24);
        for stage in [None].into_iter().chain(Stage::ALL.map(Some)) {
            let img = draw(&w, stage);
            assert!(
                img.pixels
                    .iter()
                    .all(|p| p.is_finite() && p.min_element() >= 0.0),
                "{name} {stage:?}"
            );
        }
    }
}

#[test]
fn phong_stages_add_terms_in_order() {
    let w = world("phong", W, H);
    let hits = objects(&w);
    let [inter, diffuse, specular, shadow, reflection] = Stage::ALL.map(|s| draw(&w, Some(s)));
    let full = draw(&w, None);
    assert_eq!(
        full, reflection,
        "without a stage the scene renders in full"
    );
    let mut differ = [0; 3];
    for k in 0..hits.len() {
        let (d, s, sh, r) = (
            diffuse.pixels[k],
            specular.pixels[k],
            shadow.pixels[k],
            reflection.pixels[k],
        );
        if hits[k].is_none() {
            // Background pixels are the same in every stage.
            assert!(
                d == s && s == sh && sh == r && r == inter.pixels[k],
                "pixel {k}"
            );
            continue;
        }
        assert!(s.cmpge(d).all(), "specular adds light: {k}");
        assert!(sh.cmple(s + 1e-6).all(), "shadows only remove light: {k}");
        assert!(r.cmpge(sh - 1e-6).all(), "reflection only adds light: {k}");
        differ[0] += (s != d) as usize;
        differ[1] += (sh != s) as usize;
        differ[2] += (r != sh) as usize;
    }
    assert!(
        differ.iter().all(|&n| n > 20),
        "each stage changes many pixels: {differ:?}"
    );
}

#[test]
fn floor_in_shadow_is_darker_than_lit_floor() {
    let w = world("phong", W, H);
    let hits = objects(&w);
    let img = draw(&w, Some(Stage::Shadow));
    let unshadowed = draw(&w, Some(Stage::Specular));
    let floor = 1; // objects: kitten, floor
    let (mut dark, mut lit) = (vec![], vec![]);
    for k in 0..hits.len() {
        if hits[k] == Some(floor) {
            let l = luminance(img.pixels[k]);
            if img.pixels[k] != unshadowed.pixels[k] {
                dark.push(l)
            } else {
                lit.push(l)
            }
        }
    }
    assert!(
        dark.len() > 30 && lit.len() > 30,
        "{} {}",
        dark.len(),
        lit.len()
    );
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    assert!(
        mean(&dark) < 0.8 * mean(&lit),
        "shadowed {} vs lit {}",
        mean(&dark),
        mean(&lit)
    );
}

#[test]
fn reflection_differs_from_shadow_only_on_reflective_surfaces() {
    // In the cubemap scene only the kitten (ks = 0.85) reflects; background pixels are equal.
    let w = world("cubemap", W, H);
    let hits = objects(&w);
    let shadow = draw(&w, Some(Stage::Shadow));
    let reflection = draw(&w, Some(Stage::Reflection));
    let mut changed = 0;
    for k in 0..hits.len() {
        match hits[k] {
            None => assert_eq!(shadow.pixels[k], reflection.pixels[k]),
            Some(_) => changed += (shadow.pixels[k] != reflection.pixels[k]) as usize,
        }
    }
    let kitten = hits.iter().filter(|h| h.is_some()).count();
    assert!(
        changed as f32 > 0.95 * kitten as f32,
        "{changed} of {kitten}"
    );
}

#[test]
fn refraction_shows_the_cube_map_through_the_kitten() {
    let w = world("refraction", W, H);
    let hits = objects(&w);
    let full = draw(&w, None);
    let local = draw(&w, Some(Stage::Shadow));
    let kitten: Vec<usize> = (0..hits.len()).filter(|&k| hits[k].is_some()).collect();
    let mean = |img: &Image| {
        kitten
            .iter()
            .map(|&k| luminance(img.pixels[k]))
            .sum::<f32>()
            / kitten.len() as f32
    };
    // Locally the glass has only a 0.1 highlight; what is seen is mostly the cube map behind.
    assert!(
        mean(&full) > 4.0 * mean(&local),
        "{} vs {}",
        mean(&full),
        mean(&local)
    );
    // The transmitted image varies (it is the environment, not a flat colour).
    let lum: Vec<f32> = kitten.iter().map(|&k| luminance(full.pixels[k])).collect();
    let (lo, hi) = lum
        .iter()
        .fold((f32::MAX, 0f32), |(a, b), &l| (a.min(l), b.max(l)));
    assert!(hi - lo > 0.2, "{lo}..{hi}");
}

#[test]
fn vertex_colours_and_texture_vary_over_the_kitten() {
    for name in ["vertex_color", "texture"] {
        let w = world(name, W, H);
        let hits = objects(&w);
        let img = draw(&w, Some(Stage::Diffuse));
        // Chromaticity (colour without brightness) spreads widely across the kitten.
        let chroma: Vec<Vec3> = (0..hits.len())
            .filter(|&k| hits[k] == Some(0))
            .map(|k| img.pixels[k] / img.pixels[k].element_sum().max(1e-6))
            .collect();
        let spread = chroma
            .iter()
            .map(|c| (*c - chroma[0]).length())
            .fold(0f32, f32::max);
        assert!(spread > 0.2, "{name}: {spread}");
        let phong = draw(&world("phong", W, H), Some(Stage::Diffuse));
        assert_ne!(img, phong);
    }
}

#[test]
fn depth_zero_means_no_secondary_rays() {
    let w = world("refraction", 32, 24);
    let mut s = settings(None);
    s.depth = Some(0);
    let (_, stats) = render(&w, &s, &|_| {});
    use std::sync::atomic::Ordering::Relaxed;
    assert_eq!(
        stats.rays.reflection.load(Relaxed) + stats.rays.refraction.load(Relaxed),
        0
    );
    s.depth = Some(2);
    let (_, stats) = render(&w, &s, &|_| {});
    assert!(stats.rays.refraction.load(Relaxed) > 0);
}

/// The wavefront engines and the scalar reference agree on every scene and stage. All trace
/// identical rays (intersect8 and the wide kernels' lanes equal intersect1 bit for bit, shade8
/// lanes equal the scalar shading bit for bit, see below), so pixels differ only by the order
/// in which contributions are summed: at most 1e-5 per channel against the scalar reference,
/// and the wavefront engines (packet, wide, hybrid, auto: one summation order) give the same image bit
/// for bit.
#[test]
fn packet_and_scalar_engines_agree_on_every_scene_and_stage() {
    use whitted::render::Engine;
    for name in whitted::scenes::NAMES {
        let w = world(name, 40, 30);
        for stage in [None].into_iter().chain(Stage::ALL.map(Some)) {
            for spp in [1, 4] {
                let mut s = settings(stage);
                s.spp = spp;
                s.engine = Engine::Scalar;
                let (a, sa) = render(&w, &s, &|_| {});
                s.engine = Engine::Packet;
                let (b, sb) = render(&w, &s, &|_| {});
                for other in [
                    Engine::Wide,
                    Engine::Hybrid,
                    Engine::Packet16,
                    Engine::Hybrid16,
                    Engine::Auto,
                ] {
                    s.engine = other;
                    let (c, sc) = render(&w, &s, &|_| {});
                    let bits = |i: &whitted::image::Image| {
                        i.pixels
                            .iter()
                            .map(|p| p.to_array().map(f32::to_bits))
                            .collect::<Vec<_>>()
                    };
                    assert!(
                        bits(&b) == bits(&c),
                        "{name} {stage:?} spp {spp}: {other:?} differs from packet"
                    );
                    assert_eq!(sb.rays.total(), sc.rays.total());
                }
                let max = a
                    .pixels
                    .iter()
                    .zip(&b.pixels)
                    .map(|(p, q)| (*p - *q).abs().max_element())
                    .fold(0f32, f32::max);
                assert!(
                    max <= 1e-5,
                    "{name} {stage:?} spp {spp}: max difference {max}"
                );
                use std::sync::atomic::Ordering::Relaxed;
                assert_eq!(
                    sa.rays.total(),
                    sb.rays.total(),
                    "{name} {stage:?}: same rays traced"
                );
                assert_eq!(sa.rays.shadow.load(Relaxed), sb.rays.shadow.load(Relaxed));
            }
        }
    }
}

/// `shade8` is the lane twin of the scalar shading: for every lane of camera packets and of
/// the reflection / refraction packets they spawn, on every scene (with a non-integer Phong
/// exponent on one material, so both exponent paths run), it computes bit for bit what
/// `surface`, `direct1`, `shadow_ray` and `secondaries1` compute.
#[test]
fn shade8_lanes_equal_the_scalar_shading_bit_for_bit() {
    use whitted::accel::intersect8;
    use whitted::packet::{PacketShape, RayPacket8, camera_packet};
    use whitted::render::Terms;
    use whitted::shade::{Shade8, direct1, secondaries1, shade8, shadow_ray, surface};
    use whitted::simd;
    let bits3 = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut lanes_checked = 0;
    for (name, odd_exponent, rgb) in [
        ("phong", false, false),
        ("phong", true, false),
        ("phong", false, true),
        ("vertex_color", false, false),
        ("texture", false, false),
        ("cubemap", false, false),
        ("refraction", true, false),
        ("refraction", false, true),
        ("demo", false, false),
    ] {
        let mut w = world(name, 64, 48);
        if odd_exponent {
            w.scene.materials[0].n = 33.3;
        }
        if rgb {
            // RGB coefficients that differ per channel, a separate reflection weight and an
            // emitting material (one channel zero, so masks see mixed channels).
            let m = &mut w.scene.materials[0];
            m.ka = Vec3::new(0.3, 0.1, 0.0);
            m.kd = Vec3::new(0.7, 0.2, 0.5);
            m.ks = Vec3::new(0.0, 0.25, 0.6);
            m.kr = Vec3::new(0.4, 0.0, 0.1);
            m.kt = Vec3::new(0.0, 0.9, 0.3) * (name == "refraction") as u32 as f32;
            m.ke = Vec3::new(0.5, 0.0, 0.25);
        }
        let cam = w.scene.camera();
        let terms = Terms::of(None);
        let cull = w.scene.cull_backfaces;
        let mut out = Shade8::default();
        let mut queue: Vec<(RayPacket8, simd::M32x8)> = Vec::new();
        for y in (0..cam.height).step_by(2) {
            for x in (0..cam.width).step_by(4) {
                queue.push(camera_packet(&cam, PacketShape::Block4x2, x, y, 0.5, 0.5));
            }
        }
        for generation in 0..3 {
            let mut next = Vec::new();
            for (packet, active) in &queue {
                let hits = intersect8(&w.accel, packet, *active, cull);
                let mask = hits.hit_mask() & *active;
                let depth = [2 - generation; 8];
                shade8(&w, terms, packet, &hits, mask, depth, &mut out);
                let mut spawned = [None; 2].map(|_: Option<()>| [None; 8]);
                for i in (0..8).filter(|&i| simd::lane_set(mask, i)) {
                    let (ray, hit) = (packet.lane(i), hits.lane(i).unwrap());
                    let s = surface(&w, &ray, &hit);
                    let direct = direct1(&w, terms, &s, ray.dir, |_| true);
                    let mut sum = Vec3::from(out.ambient.lane(i));
                    for (l, light) in out.lights.iter().zip(&w.scene.lights) {
                        if simd::lane_set(l.lit, i) {
                            sum += Vec3::from(l.contribution.lane(i));
                            let r = shadow_ray(&s, light.position, w.eps);
                            assert_eq!(bits3(Vec3::from(l.origin.lane(i))), bits3(r.origin));
                            assert_eq!(bits3(Vec3::from(l.dir.lane(i))), bits3(r.dir));
                            assert_eq!(simd::lanes(l.tfar)[i].to_bits(), r.tfar.to_bits());
                        }
                    }
                    assert_eq!(bits3(sum), bits3(direct), "{name} lane {i}");
                    let scalar = secondaries1(&w, &s, ray.dir, depth[i]);
                    for (k, sec) in [&out.reflection, &out.refraction].into_iter().enumerate() {
                        assert_eq!(simd::lane_set(sec.mask, i), scalar[k].is_some());
                        if let Some(r) = scalar[k] {
                            assert_eq!(bits3(Vec3::from(sec.origin.lane(i))), bits3(r.ray.origin));
                            assert_eq!(bits3(Vec3::from(sec.dir.lane(i))), bits3(r.ray.dir));
                            assert_eq!(bits3(Vec3::from(sec.weight.lane(i))), bits3(r.weight));
                            spawned[k][i] = Some(r.ray);
                        }
                    }
                    lanes_checked += 1;
                }
                for rays in spawned {
                    if rays.iter().any(Option::is_some) {
                        next.push(RayPacket8::from_fn(|i| rays[i]));
                    }
                }
            }
            queue = next;
        }
    }
    assert!(lanes_checked > 10_000, "{lanes_checked} lanes checked");
}

/// A light whose share at a hit is exactly 0 in every channel (`kd = 0` where the Phong lobe
/// rounds to 0) gets no shadow ray, in every engine, and the image is what it would be with
/// the ray traced: with `kd = ks = 0` no light can add anything, so no shadow ray is traced
/// and the image equals, bit for bit, the scene's image without its lights. On `refraction`
/// (`kd = 0`, `n = 200`) the lobe skips most rays: fewer shadow rays than with a diffuse share
/// too small to see.
#[test]
fn lights_that_add_nothing_get_no_shadow_rays() {
    use std::sync::atomic::Ordering::Relaxed;
    use whitted::render::Engine;
    let bits = |i: &Image| {
        i.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    let mut dark = world("phong", 40, 30);
    for m in &mut dark.scene.materials {
        (m.kd, m.ks) = (Vec3::ZERO, Vec3::ZERO);
    }
    let mut unlit = world("phong", 40, 30);
    unlit.scene.materials = dark.scene.materials.clone();
    unlit.scene.lights.clear();
    let shadow_rays = |w: &World, engine| {
        let mut s = settings(None);
        s.engine = engine;
        let (img, stats) = render(w, &s, &|_| {});
        (img, stats.rays.shadow.load(Relaxed))
    };
    for engine in [Engine::Scalar, Engine::Packet, Engine::Auto] {
        let (img, n) = shadow_rays(&dark, engine);
        assert_eq!(n, 0, "{engine:?}");
        assert!(
            bits(&img) == bits(&shadow_rays(&unlit, engine).0),
            "{engine:?}"
        );
    }
    let glass = world("refraction", 40, 30);
    let mut faint = world("refraction", 40, 30);
    for m in &mut faint.scene.materials {
        m.kd = Vec3::splat(1e-30);
    }
    for engine in [Engine::Scalar, Engine::Auto] {
        let (few, all) = (shadow_rays(&glass, engine).1, shadow_rays(&faint, engine).1);
        assert!(0 < few && 2 * few < all, "{engine:?}: {few} of {all}");
    }
}

/// Total internal reflection traces `It` along `d_r` from the same origin as the reflection
/// ray: the wavefront engines trace such a pair (what it spawns, and the shadow rays of its
/// hits) once. On `refraction`
/// most secondary rays are such repeats; its image stays the one of `canonical_hashes.rs`.
/// Scenes without refraction have none, and the scalar reference counts none.
#[test]
fn total_internal_reflection_pairs_are_traced_once() {
    use std::sync::atomic::Ordering::Relaxed;
    use whitted::render::Engine;
    let count = |name: &str, engine| {
        let w = world(name, 40, 30);
        let mut s = settings(None);
        s.engine = engine;
        let (_, stats) = render(&w, &s, &|_| {});
        let r = &stats.rays;
        (
            r.repeated.load(Relaxed),
            r.reflection.load(Relaxed) + r.refraction.load(Relaxed),
            r.repeated_shadow.load(Relaxed),
            r.shadow.load(Relaxed),
        )
    };
    for engine in [
        Engine::Packet,
        Engine::Wide,
        Engine::Hybrid,
        Engine::Packet16,
        Engine::Hybrid16,
        Engine::Auto,
    ] {
        let (repeated, secondary, repeated_shadow, shadow) = count("refraction", engine);
        assert!(
            3 * repeated > secondary && repeated < secondary,
            "{engine:?}: {repeated} of {secondary}"
        );
        // the shadow rays of repeated hits repeat too
        assert!(
            0 < repeated_shadow && repeated_shadow < shadow,
            "{engine:?}: {repeated_shadow} of {shadow} shadow rays"
        );
        let (r, _, rs, _) = count("cubemap", engine);
        assert_eq!((r, rs), (0, 0));
    }
    let (r, _, rs, _) = count("refraction", Engine::Scalar);
    assert_eq!((r, rs), (0, 0));
}
