//! Free disk space, so that `tumble run` can refuse a run whose outputs would not fit before
//! it writes anything (see [`crate::io::estimate::outputs`]).

use std::path::{Path, PathBuf};

/// `path` if it exists, else its nearest existing ancestor (a run directory not made yet lives
/// on the disk of the directory it will be made in); the current directory for a relative path
/// none of whose ancestors exists.
pub fn existing_ancestor(path: &Path) -> PathBuf {
    let mut p = path;
    loop {
        if p.exists() {
            return p.to_path_buf();
        }
        match p.parent() {
            Some(up) if !up.as_os_str().is_empty() => p = up,
            _ => return PathBuf::from("."),
        }
    }
}

/// The bytes an unprivileged process may still write on the file system holding `path` (or
/// its nearest existing ancestor); `None` where this is not known.
pub fn free_bytes(path: &Path) -> Option<u64> {
    available(&existing_ancestor(path))
}

#[cfg(unix)]
fn available(path: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::zeroed();
    // SAFETY: `c` is a NUL-terminated path and `st` points to a statvfs the call fills in; it
    // is read only when the call succeeds.
    let rc = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled in `st`.
    let st = unsafe { st.assume_init() };
    #[allow(clippy::unnecessary_cast)] // the field types differ between platforms
    Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

#[cfg(not(unix))]
fn available(_path: &Path) -> Option<u64> {
    None
}
