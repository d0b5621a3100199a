//! Helpers shared by the integration tests.

use std::fs;
use std::path::{Path, PathBuf};

/// A fresh, empty scratch directory unique to this process, test file and test; removed on
/// drop.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `tumble-<file>-<pid>-<test>` in the system's temporary directory.
    pub fn new(file: &str, test: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("tumble-{file}-{}-{test}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}
