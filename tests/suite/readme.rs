//! The README's first scene is a real scene: it loads, validates and runs a few steps.

use std::path::Path;

fn readme_scene() -> String {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let start = readme.find("```ron\n").expect("a ron block in the README") + "```ron\n".len();
    let len = readme[start..].find("```").expect("the ron block ends");
    readme[start..start + len].to_string()
}

#[test]
fn readme_first_scene_runs() {
    let dir = std::env::temp_dir().join(format!("tumble-readme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("my-disk.ron");
    std::fs::write(&file, readme_scene()).unwrap();
    let out = dir.join("run");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_tumble"))
        .args([
            "run",
            file.to_str().unwrap(),
            "--quiet",
            "--until",
            "0.005",
            "--out",
        ])
        .arg(&out)
        .status()
        .expect("tumble runs");
    assert!(status.success(), "the README's scene failed: {status}");
    assert!(out.join("bodies.csv").exists(), "no bodies.csv written");
    std::fs::remove_dir_all(&dir).ok();
}
