//! whitted: a data-oriented Whitted ray tracer over triangle meshes.
//!
//! Render a built-in scene (or `Scene::load("my.toml")`) and save it:
//!
//! ```
//! use whitted::{Scene, Settings};
//! let mut scene = Scene::builtin("phong")?;
//! (scene.width, scene.height) = (64, 48);
//! let image = scene.render(&Settings::default())?;
//! image.save(std::env::temp_dir().join("phong.png"))?;
//! # Ok::<(), whitted::Error>(())
//! ```
//!
//! Below the front door: [`io::scene`] parses and validates scene files (and returns
//! the loaders' warnings), [`render::World`] holds a scene with its BVH, [`render::render`]
//! renders with progress and statistics, [`trace`] traces ray files against a mesh.
// No unsafe code but two system calls (`accel::pages`: huge-page advice, the allocator's
// thresholds), the calls into the AVX-512 kernels after the CPU check (`accel::packet16`),
// the prefetch hint of the interleaved walks and the call into their AVX-512 VL build after
// the same check (`accel::wide1::interleave`) and the output file's early writeback request
// (`io::output::writeback`), allowed there alone.
#![deny(unsafe_code)]
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod aov;
pub mod api;
pub mod bench;
pub mod camera;
pub mod cpu;
pub mod engine;
pub mod error;
pub mod image;
pub mod info;
pub mod instance;
pub mod io;
pub mod mesh;
pub mod packet;
pub mod query;
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
pub use image::Image;
pub use render::{Settings, Stage};
pub use scene::Scene;
