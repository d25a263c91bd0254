//! whitted: a data-oriented Whitted ray tracer over triangle meshes.
//!
//! ```
//! use whitted::{io::scene_file::{SearchPath, build_scene}, render::{render, Settings, World}, scenes};
//! let mut file = scenes::builtin("demo").unwrap();
//! file.image.width = 32;
//! file.image.height = 24;
//! let (scene, _warnings) = build_scene(&file, "demo".as_ref(), &SearchPath::for_scene(None)).unwrap();
//! let world = World::new(scene);
//! let (image, stats) = render(&world, &Settings::default(), &|_| {});
//! assert_eq!(image.pixels.len(), 32 * 24);
//! assert!(stats.rays.total() >= 32 * 24);
//! ```
#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod aov;
pub mod bench;
pub mod camera;
pub mod error;
pub mod image;
pub mod info;
pub mod io;
pub mod mesh;
pub mod packet;
pub mod ray;
pub mod render;
pub mod scene;
pub mod scenes;
pub mod shade;
pub mod simd;
pub mod texture;
pub mod trace;
pub mod world;

pub use error::{Error, Result};
