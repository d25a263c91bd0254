//! The README's commands run: every shell block marked `<!-- runnable -->` is run with bash
//! (`-euo pipefail`) in a temporary folder, with `whitted` on `PATH` (a wrapper around the
//! built binary that renders small images and benchmarks briefly), so the README cannot go
//! stale. The set-up block and the library example are checked too.

use std::path::{Path, PathBuf};
use std::process::Command;

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap()
}

/// The fenced blocks of `text`: (info string, whether the line before the fence is
/// `<!-- runnable -->`, body).
fn blocks(text: &str) -> Vec<(String, bool, String)> {
    let mut out = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        if let Some(info) = lines[i].strip_prefix("```") {
            let runnable = i > 0 && lines[i - 1].trim() == "<!-- runnable -->";
            let mut body = String::new();
            i += 1;
            while i < lines.len() && !lines[i].starts_with("```") {
                body.push_str(lines[i]);
                body.push('\n');
                i += 1;
            }
            out.push((info.trim().to_string(), runnable, body));
        }
        i += 1;
    }
    out
}

/// Image and benchmark sizes cut down: `--width N` / `--height N` become 96 / 64, `--reps N`
/// becomes 1.
fn small(block: &str) -> String {
    let mut out = block.to_string();
    for (flag, to) in [("--width ", "96"), ("--height ", "64"), ("--reps ", "1")] {
        let mut from = 0;
        while let Some(at) = out[from..].find(flag) {
            let start = from + at + flag.len();
            let digits = out[start..]
                .chars()
                .take_while(char::is_ascii_digit)
                .count();
            if digits > 0 {
                out.replace_range(start..start + digits, to);
            }
            from = start;
        }
    }
    out
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("whitted-readme-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("bin")).unwrap();
    dir
}

/// A folder like a user's: the clone's `meshes/` and `textures/` beside it (README commands
/// run from the clone), and `bin/whitted`, which runs the built binary at small sizes.
fn workspace(name: &str) -> PathBuf {
    let dir = temp_dir(name);
    let project = Path::new(env!("CARGO_MANIFEST_DIR"));
    for d in ["meshes", "textures", "contrib"] {
        std::os::unix::fs::symlink(project.join(d), dir.join(d)).unwrap();
    }
    let wrapper = dir.join("bin/whitted");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\n\
             case \"$1\" in\n\
             render) case \" $* \" in *' --width '*) ;; *) set -- \"$@\" --width 96 --height 64 ;; esac ;;\n\
             bench) set -- \"$@\" --no-peer\n\
             case \" $* \" in *' --width '*) ;; *) set -- \"$@\" --width 96 --height 64 ;; esac\n\
             case \" $* \" in *' --reps '*) ;; *) set -- \"$@\" --reps 1 ;; esac ;;\n\
             esac\n\
             exec '{}' \"$@\"\n",
            env!("CARGO_BIN_EXE_whitted")
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

fn run_block(dir: &Path, script: &str) {
    let path = format!(
        "{}:{}",
        dir.join("bin").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let r = Command::new("bash")
        .args(["-euo", "pipefail", "-c", script])
        .current_dir(dir)
        .env("PATH", path)
        .env_remove("WHITTED_ASSETS")
        .env_remove("WHITTED_PEER")
        .output()
        .unwrap();
    assert!(
        r.status.success(),
        "README block failed ({}):\n{script}\nstdout:\n{}\nstderr:\n{}",
        r.status,
        String::from_utf8_lossy(&r.stdout),
        String::from_utf8_lossy(&r.stderr)
    );
}

#[test]
fn readme_is_at_most_500_lines() {
    let n = readme().lines().count();
    assert!(n <= 500, "README.md has {n} lines");
}

/// The first block is the set-up of a fresh clone: render the demo, run the tests. The render
/// is run (as `whitted render ...`); the tests are what is running this.
#[test]
fn setup_block_comes_first_and_renders() {
    let text = readme();
    let (info, _, body) = blocks(&text).into_iter().next().unwrap();
    assert_eq!(info, "sh");
    assert_eq!(
        body,
        "cargo run --release -- render -o demo.png\ncargo test --release\n"
    );
    let dir = workspace("setup");
    run_block(&dir, "whitted render -q -o demo.png");
    assert!(dir.join("demo.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn runnable_blocks_run() {
    let text = readme();
    let runnable: Vec<String> = blocks(&text)
        .into_iter()
        .filter(|(_, r, _)| *r)
        .map(|(info, _, body)| {
            assert_eq!(info, "sh", "runnable blocks are sh:\n{body}");
            body
        })
        .collect();
    assert!(runnable.len() >= 5, "{} runnable blocks", runnable.len());
    // One folder for all, in order: later blocks may use what earlier ones made.
    let dir = workspace("blocks");
    for block in &runnable {
        run_block(&dir, &small(block));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The library example is `examples/library.rs` verbatim, which `cargo test` compiles.
#[test]
fn library_example_is_the_example_file() {
    let text = readme();
    let rust: Vec<String> = blocks(&text)
        .into_iter()
        .filter(|(info, _, _)| info == "rust")
        .map(|(_, _, body)| body)
        .collect();
    assert_eq!(rust.len(), 1, "one rust block");
    let example =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/library.rs"))
            .unwrap();
    assert_eq!(rust[0], example);
}

#[test]
fn small_cuts_sizes_down() {
    assert_eq!(
        small("whitted render x --width 3840 --height 2160 --reps 5 -o a.png"),
        "whitted render x --width 96 --height 64 --reps 1 -o a.png"
    );
}
