use whitted::{Scene, Settings};

fn main() -> whitted::Result<()> {
    let mut scene = Scene::builtin("phong")?; // or Scene::load("my.toml")? or a mesh file
    (scene.width, scene.height) = (640, 480);
    let image = scene.render(&Settings::default())?; // Settings { stage, depth, spp, engine }
    image.save("phong.png")?; // .png (sRGB 8-bit) or .exr (linear float)
    Ok(())
}
