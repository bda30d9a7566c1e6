//! A small tmpfs for the full-disk tests (`tests/hostile3.rs`, `tests/fuzz3.rs`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// A tmpfs of `kib` KiB mounted at a fresh folder, unmounted when dropped; `None` (the test
/// says SKIPPED) where this process cannot mount (not root, no tmpfs).
pub struct Tmpfs(pub PathBuf);

impl Tmpfs {
    pub fn mount(at: &Path, kib: u64) -> Option<Tmpfs> {
        std::fs::create_dir_all(at).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kib}k"), "tmpfs"])
            .arg(at)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then(|| Tmpfs(at.to_path_buf()))
    }

    /// Bytes free on it.
    pub fn free(&self) -> u64 {
        let out = Command::new("df")
            .args(["-B1", "--output=avail"])
            .arg(&self.0)
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .nth(1)
            .and_then(|l| l.trim().parse().ok())
            .unwrap()
    }

    /// Fills it with a file until `leave` bytes are free.
    pub fn fill_leaving(&self, leave: u64) {
        let filler = self.0.join("filler");
        let _ = std::fs::remove_file(&filler);
        let n = self.free().saturating_sub(leave);
        std::fs::write(&filler, vec![0u8; n as usize]).unwrap();
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}
