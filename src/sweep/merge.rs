//! `h8swarm sweep merge`: a sweep's table ([`super::table`]) and, when the sweep folder holds
//! a confirmation ([`super::confirm`]), the confirmation's beside it, staged together and moved
//! into place in one commit.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::SweepError;

/// Merges the sweep in `dir` into `out` (default `DIR/merged`) and, when `dir` holds a
/// confirmation ([`super::confirm`]), it into `out/confirm` with the two side by side; returns
/// what to print and whether every point of both finished. Every file of both is written into
/// one staging folder and moved into place in one commit ([`crate::stage`]): a failure leaves
/// `out` as it was, map and confirmation alike.
///
/// # Errors
/// Not a sweep folder (input); an output that cannot be written (tool).
pub fn merge(dir: &Path, out: Option<&Path>) -> Result<(String, bool), SweepError> {
    let out: PathBuf = out.map_or_else(|| dir.join("merged"), Path::to_path_buf);
    let stage = crate::stage::Stage::new("--out", &out).map_err(|e| SweepError::tool(e.0))?;
    let mut done = super::table::merge_into(dir, &stage, "")?;
    // Merge's own files of an earlier merge into `out` that this one may not write again: the
    // confirmation's (a map merged without one leaves no stale confirmation beside it).
    let confirm_prefix = format!("{}/", super::confirm::CONFIRM_DIR);
    done.ours.extend(
        ["confirmation.csv", "confirmation.json"]
            .into_iter()
            .map(str::to_string),
    );
    done.ours.extend(
        ["sweep.csv", "sweep.json"]
            .into_iter()
            .map(|f| format!("{confirm_prefix}{f}")),
    );
    done.ours.extend(
        super::table::earlier_figures(&out.join(super::confirm::CONFIRM_DIR))
            .into_iter()
            .map(|f| format!("{confirm_prefix}{f}")),
    );
    if dir
        .join(super::confirm::CONFIRM_DIR)
        .join("plan.json")
        .is_file()
    {
        let _ = writeln!(done.text);
        let c = super::confirm::merge_confirmation(dir, &stage)?;
        done.text.push_str(&c.text);
        done.complete &= c.complete;
        done.files.extend(c.files);
        done.folders.extend(c.folders);
    }
    stage
        .commit(&crate::stage::Commit {
            files: done.files,
            ours: done.ours,
            folders: done.folders,
        })
        .map_err(|e| {
            SweepError::tool(format!(
                "the merge into `{}` could not be moved into place: {e}",
                out.display()
            ))
        })?;
    Ok((done.text, done.complete))
}
