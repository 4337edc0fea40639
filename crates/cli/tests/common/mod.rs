//! Set-up shared by the tests that run the `radia` binary: a temporary folder, a scene
//! written into it, `radia render` on it, and what a clean success or failure looks like.

#![allow(dead_code)] // each test binary uses its own part

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `radia` binary cargo built for these tests.
pub fn radia(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_radia"))
        .args(args)
        .output()
        .expect("radia runs")
}

/// A fresh folder for one test (named after it and this process, so that tests running at
/// once do not share files), removed with everything in it when the test is done with it.
pub fn temp_dir(name: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("radia-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// A folder that is deleted when dropped (a test's, so its files do not pile up in /tmp).
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        // Best effort: a test that failed may still hold a file open on some systems.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes `xml` as `dir/scene.xml` and returns its path.
pub fn write_scene(dir: &Path, xml: &str) -> PathBuf {
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

/// `radia render SCENE -o OUT -q EXTRA…`.
pub fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    radia(&args)
}

/// Asserts that the run succeeded (showing its stderr if not).
pub fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Asserts that the run failed cleanly: a non-zero exit that is not a panic's (101) and no
/// panic message. Returns its stderr.
pub fn assert_clean_failure(out: &Output, what: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        !out.status.success(),
        "{what}: exit status {:?}",
        out.status
    );
    assert_ne!(out.status.code(), Some(101), "{what}: panicked: {stderr}");
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    stderr
}
