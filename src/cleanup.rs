//! What an interrupted command leaves behind, removed: while a staging folder exists (`run`'s
//! `.NAME.partial-PID` beside its output folder, a sweep point's `points/.tmp-ID-HOST-PID`) it
//! is registered here; when SIGINT, SIGTERM or SIGHUP arrives, a thread of its own removes
//! every registered folder and then lets the signal end the process as it would have (so a
//! shell still sees 130 for Ctrl-C and 143 for SIGTERM). A signal the process was started
//! ignoring (under `nohup`, or SIGINT for a background job of a script) stays ignored.
//!
//! Moving a finished run's files into place holds the same lock as the cleanup
//! ([`while_committing`]): a signal that arrives during the move waits for it, so an output
//! folder is never left half old, half new. SIGKILL cannot be caught: what it leaves, the next
//! `sweep run` removes (a folder whose process is gone) and `sweep merge` lists.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, Once};

use signal_hook::consts::signal::{SIGHUP, SIGINT, SIGTERM};

/// The staging folders that exist now.
static STAGING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Held while finished files move into place (and by the cleanup, which so waits for it).
static COMMIT: Mutex<()> = Mutex::new(());
/// Set when a signal's cleanup has begun: the process is about to die of it.
static SIGNALLED: AtomicBool = AtomicBool::new(false);

/// Whether a signal's cleanup has begun. The work it stops may fail first (its staging
/// folder is gone): such a failure is not reported, the process waits for the signal to end
/// it ([`wait_if_signalled`]).
#[must_use]
pub fn signalled() -> bool {
    SIGNALLED.load(Ordering::SeqCst)
}

/// Never returns when a signal's cleanup has begun (the signal ends the process); returns at
/// once otherwise.
pub fn wait_if_signalled() {
    while signalled() {
        std::thread::park_timeout(std::time::Duration::from_secs(1));
    }
}

fn staging() -> MutexGuard<'static, Vec<PathBuf>> {
    STAGING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Starts the thread that cleans up on SIGINT, SIGTERM and SIGHUP (once; later calls do
/// nothing). Returns whether the signals are handled (they are not when they cannot be
/// registered: a process then dies of them as before, leaving its staging folders).
pub fn install() -> bool {
    static ONCE: Once = Once::new();
    let mut installed = false;
    ONCE.call_once(|| {
        // A signal the process was started ignoring (`nohup`, a background job of a script)
        // stays ignored: handling it would make it end the process.
        let ignored = ignored_signals();
        let wanted: Vec<i32> = [SIGINT, SIGTERM, SIGHUP]
            .into_iter()
            .filter(|&s| !ignored.contains(&s))
            .collect();
        if wanted.is_empty() {
            return;
        }
        let Ok(mut signals) = signal_hook::iterator::Signals::new(wanted) else {
            return;
        };
        installed = std::thread::Builder::new()
            .name("h8swarm-signals".into())
            .spawn(move || {
                if let Some(signal) = signals.forever().next() {
                    SIGNALLED.store(true, Ordering::SeqCst);
                    // Waits for a commit under way; nothing else moves in or out after this.
                    let _held = COMMIT
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner);
                    let folders = staging().clone();
                    for dir in folders.iter() {
                        remove_all(dir);
                    }
                    let _ = signal_hook::low_level::emulate_default_handler(signal);
                    // Not reached for these signals; in case it is, end as a shell would say.
                    std::process::exit(128 + signal);
                }
            })
            .is_ok();
    });
    installed
}

/// The signals this process ignores (the `SigIgn` mask of /proc/self/status; none where it
/// cannot be read).
fn ignored_signals() -> Vec<i32> {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let mask = status
        .lines()
        .find_map(|l| l.strip_prefix("SigIgn:"))
        .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
        .unwrap_or(0);
    (1..=64).filter(|s| mask & (1u64 << (s - 1)) != 0).collect()
}

/// Removes `dir` and everything in it (or the file `dir`); workers still writing into it may add a file while it
/// goes, so it is tried a few times.
fn remove_all(dir: &Path) {
    if std::fs::symlink_metadata(dir).is_ok_and(|m| !m.is_dir()) {
        let _ = std::fs::remove_file(dir);
        return;
    }
    for _ in 0..5 {
        match std::fs::remove_dir_all(dir) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {}
            _ => return,
        }
    }
}

/// A registered staging folder: removed by the signal thread if a signal comes while this
/// lives; dropping it (or [`Staged::release`]) unregisters the folder (it does not remove it).
#[derive(Debug)]
pub struct Staged {
    dir: PathBuf,
}

impl Staged {
    /// Registers `dir`.
    #[must_use]
    pub fn register(dir: &Path) -> Staged {
        staging().push(dir.to_path_buf());
        Staged {
            dir: dir.to_path_buf(),
        }
    }

    /// Unregisters the folder now (as dropping does).
    pub fn release(self) {}
}

impl Drop for Staged {
    fn drop(&mut self) {
        let mut list = staging();
        if let Some(i) = list.iter().rposition(|d| *d == self.dir) {
            list.remove(i);
        }
    }
}

/// Runs `f` (moving finished files into place) with the cleanup held off: a signal that
/// arrives meanwhile is acted on when `f` is done.
pub fn while_committing<T>(f: impl FnOnce() -> T) -> T {
    let _held = COMMIT
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    f()
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_ignored_signals_are_read_from_the_status() {
        // Whatever this process ignores, the list holds signal numbers only.
        assert!(
            super::ignored_signals()
                .iter()
                .all(|s| (1..=64).contains(s))
        );
    }
}
