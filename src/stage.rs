//! Outputs written whole or not at all: a staging folder beside the output folder, and one
//! commit that moves every finished file into place.
//!
//! `h8swarm run` and `h8swarm sweep merge` write every file into a staging folder
//! `<parent>/.<name>.partial-<pid>` beside their output folder (a file that lives elsewhere,
//! such as `run --vcd FILE`, is staged beside its own destination as `.<file>.partial-<pid>`).
//! Nothing in the output folder changes until everything is written; then [`Stage::commit`]
//! moves the earlier files of the same names (and this tool's earlier files the new output
//! no longer has) aside, moves the new ones in, and on any failure moves everything back. A
//! full disk, a file that cannot be written, an error half-way through: the output folder
//! and the outside files keep their earlier contents, byte for byte. Staging files are
//! registered with [`crate::cleanup`], so a signal removes them; a signal that arrives during
//! the moves waits for them to end.
//!
//! Output folders follow one rule ([`check_out_folder`]): a folder with a name, not a root,
//! `.` or `..`, and not a file.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use swarm::output_error::OutputError;

/// Why an output could not be staged or committed: the tool failed (exit status 1), with the
/// message to print.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct StageError(pub String);

fn io_fail(what: String, e: &std::io::Error) -> StageError {
    StageError(format!("{what}: {e}"))
}

/// Checks that `out` can be an output folder: it has a name of its own (not a root, `.` or
/// `..`, nor ending in them) and is not a file. `option` names the option in the message.
///
/// # Errors
/// What is wrong with it, in one line.
pub fn check_out_folder(option: &str, out: &Path) -> Result<String, StageError> {
    let named = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| n != "." && n != "..");
    let dotted = out
        .components()
        .next_back()
        .is_some_and(|c| matches!(c, std::path::Component::ParentDir));
    let Some(name) = named.filter(|_| !dotted) else {
        return Err(StageError(format!(
            "{option} `{}`: give a folder name (e.g. out/run1), not a root, `.` or `..`",
            out.display()
        )));
    };
    if out.exists() && !out.is_dir() {
        return Err(StageError(format!(
            "{option} `{}` is a file: give a folder (new or holding earlier results)",
            out.display()
        )));
    }
    Ok(name)
}

/// The staged path of a file that lives outside the output folder: `.<name>.partial-<pid>`
/// beside `dest` (so that the commit's rename stays on one file system).
///
/// # Errors
/// `dest` has no file name, or is a folder.
pub fn outside_staging_path(option: &str, dest: &Path) -> Result<PathBuf, StageError> {
    let Some(name) = dest.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Err(StageError(format!(
            "{option} `{}`: give a file name",
            dest.display()
        )));
    };
    if dest.is_dir() {
        return Err(StageError(format!(
            "{option} `{}` is a folder: give a file",
            dest.display()
        )));
    }
    Ok(dest.with_file_name(format!(".{name}.partial-{}", std::process::id())))
}

/// A staging folder beside an output folder, registered for removal on a signal while it
/// exists.
#[derive(Debug)]
pub struct Stage {
    out: PathBuf,
    dir: PathBuf,
    registered: Option<crate::cleanup::Staged>,
    outside: Vec<(PathBuf, PathBuf, crate::cleanup::Staged)>,
}

/// What a commit moves: the staged files (paths relative to the staging folder, the same
/// relative paths under the output folder; at most one folder deep, such as `plots/a.png`),
/// and this tool's earlier files in the output folder that go when the new output does not
/// have them.
#[derive(Debug, Default, Clone)]
pub struct Commit {
    /// Staged files, relative paths.
    pub files: Vec<String>,
    /// This tool's files that are removed when not among `files` (relative paths).
    pub ours: Vec<String>,
    /// Sub-folders of the output folder that exist after the commit even when no file goes
    /// into them (relative paths).
    pub folders: Vec<String>,
}

/// One move of a commit, for the way back.
struct Moved {
    from: PathBuf,
    to: PathBuf,
}

impl Stage {
    /// Makes the staging folder `<parent>/.<name>.partial-<pid>` for the output folder `out`
    /// (checked by [`check_out_folder`] under the name `option`).
    ///
    /// # Errors
    /// A bad output folder; a staging folder that cannot be created.
    pub fn new(option: &str, out: &Path) -> Result<Stage, StageError> {
        let name = check_out_folder(option, out)?;
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let dir = parent.join(format!(".{name}.partial-{}", std::process::id()));
        let registered = crate::cleanup::Staged::register(&dir);
        std::fs::create_dir_all(&dir).map_err(|e| {
            io_fail(
                format!(
                    "cannot create the staging folder `{}` beside the output folder",
                    dir.display()
                ),
                &e,
            )
        })?;
        Ok(Stage {
            out: out.to_path_buf(),
            dir,
            registered: Some(registered),
            outside: Vec::new(),
        })
    }

    /// The staging folder.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The output folder.
    #[must_use]
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// Where the file `rel` (a path relative to the output folder) is written while staged.
    #[must_use]
    pub fn path(&self, rel: &str) -> PathBuf {
        self.dir.join(rel)
    }

    /// Stages a file that lives outside the output folder (`dest`): returns the path to write
    /// it to (beside `dest`, [`outside_staging_path`]); the commit moves it to `dest` with the
    /// rest, and a failure or a signal removes it. Nothing is created yet.
    ///
    /// # Errors
    /// `dest` is no file name or is a folder.
    pub fn stage_outside(&mut self, option: &str, dest: &Path) -> Result<PathBuf, StageError> {
        let staged = outside_staging_path(option, dest)?;
        let registered = crate::cleanup::Staged::register(&staged);
        self.outside
            .push((staged.clone(), dest.to_path_buf(), registered));
        Ok(staged)
    }

    /// Stages a file outside the output folder as [`Stage::stage_outside`] does and creates
    /// it empty now, so that a file that cannot be written fails before the work, not after.
    ///
    /// # Errors
    /// As [`Stage::stage_outside`], or the file cannot be created (both an
    /// [`OutputError`]: the tool failed).
    pub fn create_outside(&mut self, option: &str, dest: &Path) -> anyhow::Result<PathBuf> {
        use anyhow::Context as _;
        let staged = self
            .stage_outside(option, dest)
            .map_err(|e| anyhow::Error::new(OutputError(e.0)))?;
        std::fs::write(&staged, b"")
            .map_err(anyhow::Error::new)
            .context(OutputError(format!(
                "{option}: cannot create `{}`",
                dest.display()
            )))?;
        Ok(staged)
    }

    /// Moves the staged files into place, all or nothing (see the module's docs), and
    /// removes the staging folder. A signal that arrives meanwhile waits for the moves.
    ///
    /// # Errors
    /// Something in the way is a folder, or a move failed (everything was moved back; if even
    /// that failed, the message says where the earlier files are).
    pub fn commit(mut self, c: &Commit) -> Result<(), StageError> {
        let result = crate::cleanup::while_committing(|| self.move_into_place(c));
        match result {
            Ok(()) => {
                let _ = std::fs::remove_dir_all(&self.dir);
                self.registered.take();
                self.outside.clear();
                Ok(())
            }
            Err(e) => {
                let kept = self.remove_or_say();
                Err(if kept.is_empty() {
                    e
                } else {
                    StageError(format!("{e}; {kept}"))
                })
            }
        }
    }

    fn move_into_place(&self, c: &Commit) -> Result<(), StageError> {
        let new: BTreeSet<&str> = c.files.iter().map(String::as_str).collect();
        let replaced: BTreeSet<&str> = c
            .ours
            .iter()
            .map(String::as_str)
            .chain(new.iter().copied())
            .collect();
        // Checked before anything moves: what is in the way must be a file (ours, earlier).
        let in_the_way = |to: &Path| -> Result<(), StageError> {
            match std::fs::symlink_metadata(to) {
                Ok(meta) if meta.is_dir() => Err(StageError(format!(
                    "cannot replace `{}`: it is a folder, not a file h8swarm wrote; move it away and run again (nothing was changed)",
                    to.display()
                ))),
                _ => Ok(()),
            }
        };
        for rel in &replaced {
            in_the_way(&self.out.join(rel))?;
        }
        for (_, dest, _) in &self.outside {
            in_the_way(dest)?;
        }
        // The folders the new files need (the output folder and its sub-folders), made now and
        // removed again on the way back.
        let mut made: Vec<PathBuf> = Vec::new();
        let mut need: Vec<PathBuf> = vec![self.out.clone()];
        need.extend(c.folders.iter().map(|f| self.out.join(f)));
        for rel in &new {
            if let Some(p) = Path::new(rel)
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
            {
                need.push(self.out.join(p));
            }
        }
        need.sort();
        need.dedup();
        for d in &need {
            if !d.exists() {
                std::fs::create_dir_all(d).map_err(|e| {
                    io_fail(format!("cannot create the folder `{}`", d.display()), &e)
                })?;
                made.push(d.clone());
            }
        }
        let aside = self.dir.join(".earlier");
        let mut done: Vec<Moved> = Vec::new();
        let result = (|| -> Result<(), StageError> {
            std::fs::create_dir_all(&aside)
                .map_err(|e| io_fail(format!("cannot create `{}`", aside.display()), &e))?;
            let mv = |from: PathBuf, to: PathBuf, done: &mut Vec<Moved>, what: &str| {
                std::fs::rename(&from, &to).map_err(|e| io_fail(what.to_string(), &e))?;
                done.push(Moved { from, to });
                Ok::<(), StageError>(())
            };
            for (k, rel) in replaced.iter().enumerate() {
                let from = self.out.join(rel);
                if std::fs::symlink_metadata(&from).is_ok() {
                    let what = format!("cannot move the earlier `{}` aside", from.display());
                    mv(from, aside.join(k.to_string()), &mut done, &what)?;
                }
            }
            for (staged, dest, _) in &self.outside {
                if std::fs::symlink_metadata(dest).is_ok() {
                    let what = format!("cannot move the earlier `{}` aside", dest.display());
                    let to = outside_aside(dest);
                    mv(dest.clone(), to, &mut done, &what)?;
                }
                let what = format!("cannot move `{}` into place", dest.display());
                mv(staged.clone(), dest.clone(), &mut done, &what)?;
            }
            for rel in &new {
                let what = format!("cannot move `{rel}` into `{}`", self.out.display());
                mv(self.dir.join(rel), self.out.join(rel), &mut done, &what)?;
            }
            Ok(())
        })();
        match result {
            Ok(()) => {
                for (_, dest, _) in &self.outside {
                    let _ = std::fs::remove_file(outside_aside(dest));
                }
                Ok(())
            }
            Err(e) => {
                // Back as it was, in the reverse order.
                for m in done.iter().rev() {
                    let _ = std::fs::rename(&m.to, &m.from);
                }
                for d in made.iter().rev() {
                    let _ = std::fs::remove_dir(d);
                }
                Err(e)
            }
        }
    }

    /// After a failed commit: removes the staging files unless earlier files could not be
    /// moved back out of the staging folder; says which.
    fn remove_or_say(&mut self) -> String {
        for (staged, _, _) in &self.outside {
            let _ = std::fs::remove_file(staged);
        }
        self.outside.clear();
        let aside = self.dir.join(".earlier");
        let stranded = std::fs::read_dir(&aside).map(|d| d.count()).unwrap_or(0);
        if stranded == 0 {
            let _ = std::fs::remove_dir_all(&self.dir);
            self.registered.take();
            String::new()
        } else {
            self.registered.take();
            format!(
                "{stranded} earlier files could not be moved back: they are in `{}`",
                aside.display()
            )
        }
    }

    /// Removes the staging folder and files after a failure; says what became of the output
    /// folder.
    #[must_use]
    pub fn abandon(mut self) -> String {
        let _ = std::fs::remove_dir_all(&self.dir);
        for (staged, _, _) in &self.outside {
            let _ = std::fs::remove_file(staged);
        }
        self.outside.clear();
        self.registered.take();
        if self.out.is_dir() {
            "the earlier results there are untouched".to_string()
        } else {
            "nothing was written".to_string()
        }
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        // A stage dropped without a commit (an early return): its files go.
        if self.registered.is_some() {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
        for (staged, _, _) in &self.outside {
            let _ = std::fs::remove_file(staged);
        }
    }
}

/// Where the earlier file at `dest` (outside the output folder) waits during a commit.
fn outside_aside(dest: &Path) -> PathBuf {
    let name = dest
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    dest.with_file_name(format!(".{name}.earlier-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("h8swarm-stage-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn output_folders_need_a_name_of_their_own() {
        for bad in ["/", ".", "..", "a/..", "./..", ""] {
            assert!(
                check_out_folder("--out", Path::new(bad)).is_err(),
                "{bad:?}"
            );
        }
        assert_eq!(check_out_folder("--out", Path::new("x/y")).unwrap(), "y");
        let d = scratch("file");
        let f = d.join("f");
        std::fs::write(&f, "x").unwrap();
        let e = check_out_folder("--out", &f).unwrap_err().0;
        assert!(e.contains("is a file"), "{e}");
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn a_commit_replaces_ours_keeps_the_users_and_moves_outside_files() {
        let d = scratch("commit");
        let out = d.join("out");
        std::fs::create_dir_all(out.join("plots")).unwrap();
        std::fs::write(out.join("a.csv"), "old a").unwrap();
        std::fs::write(out.join("plots/old.png"), "old fig").unwrap();
        std::fs::write(out.join("plots/mine.png"), "user's").unwrap();
        std::fs::write(out.join("notes.txt"), "user's").unwrap();
        let vcd = d.join("trace.vcd");
        std::fs::write(&vcd, "old trace").unwrap();
        let mut s = Stage::new("--out", &out).unwrap();
        std::fs::create_dir_all(s.path("plots")).unwrap();
        std::fs::write(s.path("a.csv"), "new a").unwrap();
        std::fs::write(s.path("plots/new.png"), "new fig").unwrap();
        let staged = s.stage_outside("--vcd", &vcd).unwrap();
        std::fs::write(&staged, "new trace").unwrap();
        assert_eq!(std::fs::read_to_string(&vcd).unwrap(), "old trace");
        let stage_dir = s.dir().to_path_buf();
        s.commit(&Commit {
            files: vec!["a.csv".into(), "plots/new.png".into()],
            ours: vec!["plots/old.png".into()],
            folders: vec!["plots".into(), "empty".into()],
        })
        .unwrap();
        let read = |p: &str| std::fs::read_to_string(out.join(p)).ok();
        assert_eq!(read("a.csv").as_deref(), Some("new a"));
        assert_eq!(read("plots/new.png").as_deref(), Some("new fig"));
        assert_eq!(read("plots/old.png"), None);
        assert_eq!(read("plots/mine.png").as_deref(), Some("user's"));
        assert_eq!(read("notes.txt").as_deref(), Some("user's"));
        assert!(out.join("empty").is_dir());
        assert_eq!(std::fs::read_to_string(&vcd).unwrap(), "new trace");
        assert!(!stage_dir.exists() && !staged.exists());
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left.len(), 2, "{left:?}");
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn a_failed_commit_leaves_everything_as_it_was() {
        let d = scratch("fail");
        let out = d.join("out");
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("a.csv"), "old a").unwrap();
        std::fs::write(out.join("b.json"), "old b").unwrap();
        let vcd = d.join("trace.vcd");
        std::fs::write(&vcd, "old trace").unwrap();
        let mut s = Stage::new("--out", &out).unwrap();
        std::fs::write(s.path("a.csv"), "new a").unwrap();
        let staged = s.stage_outside("--vcd", &vcd).unwrap();
        std::fs::write(&staged, "new trace").unwrap();
        // b.json was never staged: its move fails after a.csv's earlier file and the trace
        // have moved.
        let e = s
            .commit(&Commit {
                files: vec!["a.csv".into(), "b.json".into()],
                ours: vec![],
                folders: vec!["new".into()],
            })
            .unwrap_err();
        assert!(e.0.contains("b.json"), "{e}");
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "old a");
        assert_eq!(
            std::fs::read_to_string(out.join("b.json")).unwrap(),
            "old b"
        );
        assert_eq!(std::fs::read_to_string(&vcd).unwrap(), "old trace");
        assert!(!out.join("new").exists());
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left.len(), 2, "{left:?}");
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn a_folder_in_the_way_stops_the_commit_before_anything_moves() {
        let d = scratch("dir");
        let out = d.join("out");
        std::fs::create_dir_all(out.join("a.csv")).unwrap();
        std::fs::write(out.join("b.json"), "old b").unwrap();
        let s = Stage::new("--out", &out).unwrap();
        std::fs::write(s.path("a.csv"), "new a").unwrap();
        std::fs::write(s.path("b.json"), "new b").unwrap();
        let e = s
            .commit(&Commit {
                files: vec!["b.json".into(), "a.csv".into()],
                ours: vec![],
                folders: vec![],
            })
            .unwrap_err();
        assert!(e.0.contains("is a folder"), "{e}");
        assert_eq!(
            std::fs::read_to_string(out.join("b.json")).unwrap(),
            "old b"
        );
        let _ = std::fs::remove_dir_all(d);
    }
}
