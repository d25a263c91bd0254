//! The TOML scene format, by concern: the schema ([`schema`]: what a file may say, its
//! defaults and caps), reading the text ([`text`], its `[[instance]]` tables one at a time), `-D` overrides ([`overrides`]), the
//! search path for the files a scene names ([`search`]), and building a
//! [`Scene`](crate::scene::Scene) from it ([`build`], with its materials and meshes).
//!
//! Relative file names resolve against the scene file's folder, then the current folder, then
//! each folder of `WHITTED_ASSETS` (`:`-separated). See the README for the format.
//!
//! The mesh loaders depend on [`schema`] alone (for the materials their files bring); the
//! builder depends on the loaders.

pub mod build;
mod instance_text;
mod instances;
mod materials;
pub mod meshes;
pub mod overrides;
pub mod schema;
pub mod search;
pub mod text;

pub use build::build_scene;
pub use meshes::SPHERE_SEGMENTS;
pub use overrides::{name_overrides, overrides_named};
pub use schema::*;
pub use search::{PROJECT_DATA, SearchPath};
pub use text::KeyLines;

#[cfg(test)]
mod tests;
