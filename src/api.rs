//! The front door: a scene by name or from a file, rendered and saved in five lines.
//!
//! These wrap the layers below ([`SceneFile`] and [`build_scene`] for loading, [`World`] and
//! [`render::render`](crate::render::render) for rendering, [`save_image`] for writing), which
//! stay available for what the front door leaves out: loader warnings, progress, statistics,
//! one BVH rendered many times.

use crate::error::{Error, Result};
use crate::image::Image;
use crate::io::image::save_image;
use crate::io::scene::{MAX_DEPTH, SceneFile, SearchPath, build_scene, check_size};
use crate::render::{MAX_SAMPLE_SECONDARY_RAYS, RenderStats, Settings, World};
use crate::scene::Scene;
use crate::scenes;
use std::path::{Path, PathBuf};

/// Most samples per pixel a render takes.
pub const MAX_SPP: u32 = 4096;

impl Scene {
    /// A built-in scene by name (one of [`scenes::NAMES`]: the five canonical scenes and
    /// `demo`), loaded from the data shipped with whitted (see
    /// [`PROJECT_DATA`](crate::io::scene::PROJECT_DATA)), at its default size. Loader
    /// warnings are dropped; [`scenes::builtin`] and [`build_scene`] return them.
    pub fn builtin(name: &str) -> Result<Scene> {
        let file = scenes::builtin(name).ok_or_else(|| {
            Error::Usage(format!(
                "no built-in scene '{name}' (try {})",
                scenes::NAMES.join(", ")
            ))
        })?;
        let label = PathBuf::from(format!("<built-in scene {name}>"));
        build_scene(&file, &label, &SearchPath::for_scene(None)).map(|(s, _)| s)
    }

    /// A TOML scene file, validated, with every file it names loaded (relative names resolve
    /// as [`SearchPath::for_scene`] says), or a mesh file alone (`.m`, `.obj`, `.ply`, `.stl`,
    /// `.gltf`, `.glb`), framed at 1024x768 as `whitted render model.obj` frames it (see
    /// [`scene_for_mesh`](crate::io::mesh_scene::scene_for_mesh)). Loader warnings are
    /// dropped; [`SceneFile::load`] and [`build_scene`] return them.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        let path = path.as_ref();
        let (file, dir) = if crate::io::mesh_scene::is_mesh_file(path) {
            let (file, _) = crate::io::mesh_scene::scene_for_mesh(path, 1024, 768)?;
            (file, None)
        } else {
            (SceneFile::load(path)?, path.parent())
        };
        build_scene(&file, path, &SearchPath::for_scene(dir)).map(|(s, _)| s)
    }

    /// Render the scene at its `width` x `height` (which may be changed after loading;
    /// checked again here). Builds the BVH of a copy of the scene each call: to render one
    /// scene several times, build a [`World`] once and call [`World::render_image`].
    pub fn render(&self, settings: &Settings) -> Result<Image> {
        check_size(self.width as u64, self.height as u64).map_err(Error::Usage)?;
        check_settings(settings)?;
        World::new(self.clone()).render_image(settings)
    }
}

impl World {
    /// Render into an image, or fail when the settings are out of range or a camera sample's
    /// rays were trapped (see [`MAX_SAMPLE_SECONDARY_RAYS`]). No progress reports: for those
    /// and the statistics, call [`render::render`](crate::render::render).
    pub fn render_image(&self, settings: &Settings) -> Result<Image> {
        check_size(self.scene.width as u64, self.scene.height as u64).map_err(Error::Usage)?;
        check_settings(settings)?;
        let (image, stats) = crate::render::render(self, settings, &|_| {});
        match stats.budget_error(self, settings) {
            Some(msg) => Err(Error::Usage(msg)),
            None => Ok(image),
        }
    }
}

/// `settings.depth` within [`MAX_DEPTH`] and `settings.spp` in `1..=MAX_SPP`.
fn check_settings(settings: &Settings) -> Result<()> {
    if let Some(d) = settings.depth
        && d > MAX_DEPTH
    {
        return Err(Error::Usage(format!(
            "depth {d} is over the cap of {MAX_DEPTH}"
        )));
    }
    if !(1..=MAX_SPP).contains(&settings.spp) {
        return Err(Error::Usage(format!(
            "spp {} must be in 1..={MAX_SPP}",
            settings.spp
        )));
    }
    Ok(())
}

impl RenderStats {
    /// Why the render's image must not be used, if a camera sample passed the ray budget: the
    /// pixel, the depth and what to do about it.
    pub fn budget_error(&self, world: &World, settings: &Settings) -> Option<String> {
        let (x, y) = self.over_budget_pixel(world.scene.width)?;
        Some(format!(
            "pixel ({x}, {y}): a camera sample spawned over {MAX_SAMPLE_SECONDARY_RAYS} \
             reflection and refraction rays (render.depth {}): rays are trapped between \
             surfaces that both reflect and refract; lower render.depth (--depth)",
            settings.depth(&world.scene)
        ))
    }
}

impl Image {
    /// Write the image: `.png` clamped and sRGB-encoded 8-bit, `.exr` linear float (see
    /// [`save_image`]).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        save_image(self, path.as_ref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_door_renders_and_refuses_bad_sizes_and_settings() {
        let mut scene = Scene::builtin("demo").unwrap();
        (scene.width, scene.height) = (16, 12);
        let image = scene.render(&Settings::default()).unwrap();
        assert_eq!((image.width, image.height), (16, 12));
        assert!(image.pixels.iter().any(|p| p.max_element() > 0.0));

        let e = Scene::builtin("nope").unwrap_err().to_string();
        assert!(
            e.contains("no built-in scene 'nope'") && e.contains("phong"),
            "{e}"
        );
        scene.width = 0;
        assert!(scene.render(&Settings::default()).is_err());
        scene.width = 16;
        for bad in [
            Settings {
                spp: 0,
                ..Settings::default()
            },
            Settings {
                depth: Some(MAX_DEPTH + 1),
                ..Settings::default()
            },
        ] {
            assert!(scene.render(&bad).is_err(), "{bad:?}");
        }
    }
}
