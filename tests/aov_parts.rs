//! AOV layers captured over a part of the image (as the streamed writer does, batch by
//! batch, for `--tile`, `--crop` and whole images) hold exactly the whole-image capture's
//! pixels.

mod common;

use whitted::aov::{Aov, AovImages, capture};
use whitted::image::PixelBounds;
use whitted::render::aov::capture_part;

/// The rows and columns of `part` cut out of a whole-image capture.
fn cut(all: &AovImages, part: PixelBounds) -> AovImages {
    let w = all.width;
    let pick = |i: usize| {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        (part.x0..part.x1).contains(&x) && (part.y0..part.y1).contains(&y)
    };
    fn keep<T: Copy>(v: &Option<Vec<T>>, pick: &dyn Fn(usize) -> bool) -> Option<Vec<T>> {
        v.as_ref().map(|v| {
            v.iter()
                .enumerate()
                .filter(|(i, _)| pick(*i))
                .map(|(_, p)| *p)
                .collect()
        })
    }
    AovImages {
        width: part.width() as usize,
        height: part.height() as usize,
        albedo: keep(&all.albedo, &pick),
        normal: keep(&all.normal, &pick),
        depth: keep(&all.depth, &pick),
        id: keep(&all.id, &pick),
    }
}

fn bits(a: &AovImages) -> Vec<u32> {
    let mut v = Vec::new();
    for x in [&a.albedo, &a.normal].into_iter().flatten() {
        v.extend(x.iter().flat_map(|p| p.to_array().map(f32::to_bits)));
    }
    v.extend(a.depth.iter().flatten().map(|d| d.to_bits()));
    v.extend(a.id.iter().flatten());
    v
}

#[test]
fn parts_of_the_aov_layers_equal_the_whole_capture_bit_for_bit() {
    for scene in ["phong", "texture", "refraction"] {
        let world = common::world(scene, 61, 43);
        let all = capture(&world, &Aov::ALL);
        let full = PixelBounds::full(61, 43);
        assert_eq!(bits(&capture_part(&world, &Aov::ALL, full)), bits(&all));
        for part in [
            PixelBounds {
                x0: 0,
                x1: 61,
                y0: 16,
                y1: 32,
            },
            PixelBounds {
                x0: 3,
                x1: 58,
                y0: 1,
                y1: 42,
            },
            PixelBounds {
                x0: 13,
                x1: 14,
                y0: 7,
                y1: 8,
            },
            PixelBounds {
                x0: 60,
                x1: 61,
                y0: 42,
                y1: 43,
            },
            PixelBounds {
                x0: 5,
                x1: 22,
                y0: 0,
                y1: 3,
            },
        ] {
            let got = capture_part(&world, &Aov::ALL, part);
            assert_eq!(
                (got.width, got.height),
                (part.width() as usize, part.height() as usize)
            );
            assert!(bits(&got) == bits(&cut(&all, part)), "{scene} {part}");
        }
        let some = capture_part(&world, &[Aov::Depth], full);
        assert!(some.albedo.is_none() && some.id.is_none());
        assert_eq!(some.depth, all.depth);
    }
}
