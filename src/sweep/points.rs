//! A point's folder under `points/` as `sweep run` leaves it and `sweep merge` reads it: its
//! `status.json`, its state (missing, finished, failed or broken), its `summary.json`, and the
//! temporary folders a task leaves behind, with the machine and process they belong to.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::plan::PlanLine;

/// `status.json` of a point's folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// The point's id.
    pub id: String,
    /// `ok` or `failed`.
    pub status: String,
    /// Why it failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The state of a point's folder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PointState {
    /// No folder.
    Missing,
    /// Finished.
    Ok,
    /// Ran and failed, with why.
    Failed(String),
    /// A folder that is neither: no or a bad `status.json`, another scenario, or a finished
    /// point whose `summary.json` cannot be read.
    Broken(String),
}

/// The state of `line`'s folder under `points`.
#[must_use]
pub fn point_state(points: &Path, line: &PlanLine) -> PointState {
    let dir = points.join(&line.id);
    if !dir.exists() {
        return PointState::Missing;
    }
    let status: Status = match std::fs::read_to_string(dir.join("status.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
    {
        Some(s) => s,
        None => return PointState::Broken("no readable status.json".into()),
    };
    let planned = toml::to_string(&line.scenario).unwrap_or_default();
    match std::fs::read_to_string(dir.join("scenario.toml")) {
        Ok(t) if t == planned => {}
        _ => return PointState::Broken("its scenario.toml is not the planned one".into()),
    }
    match (status.id == line.id, status.status.as_str()) {
        (true, "ok") => match read_summary(&dir.join("summary.json")) {
            Ok(_) => PointState::Ok,
            Err(why) => PointState::Broken(format!("finished, but {why}")),
        },
        (true, "failed") => PointState::Failed(status.error.unwrap_or_default()),
        _ => PointState::Broken(format!("status.json says {:?}", status.status)),
    }
}

/// A finished point's `summary.json`, or why it cannot be read (an object with its
/// `conditions` and `claims`).
pub fn read_summary(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("its summary.json cannot be read: {e}"))?;
    let v: Value =
        serde_json::from_str(&text).map_err(|e| format!("its summary.json is not JSON: {e}"))?;
    if !(v["conditions"].is_array() && v["claims"].is_array()) {
        return Err("its summary.json has no `conditions` and `claims` lists".into());
    }
    Ok(v)
}

/// This machine's name as temporary folders carry it: `HOSTNAME`, else `SLURMD_NODENAME`,
/// else the kernel's host name, reduced to `[A-Za-z0-9.+-]` (at most 32 characters).
#[must_use]
pub fn host_name() -> String {
    let name = std::env::var("HOSTNAME")
        .or_else(|_| std::env::var("SLURMD_NODENAME"))
        .ok()
        .or_else(|| {
            std::fs::read_to_string("/proc/sys/kernel/hostname")
                .ok()
                .map(|h| h.trim().to_string())
        })
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "host".into());
    super::spec::sanitize(&name, 32)
}

/// A temporary folder under `points/` (`.tmp-ID-HOST-PID`, or its run's staging folder
/// `..tmp-ID-HOST-PID.partial-PID`): whether it is a leftover of a process of this machine
/// that is gone (its PID no longer runs), so that nothing can still be writing into it.
/// Folders of other machines, and any whose process runs or cannot be told, are not.
#[must_use]
pub fn is_dead_leftover(name: &str, host: &str) -> bool {
    if !(name.starts_with(".tmp-") || name.starts_with("..tmp-")) {
        return false;
    }
    let base = name.split(".partial-").next().unwrap_or(name);
    let pid_of = |s: &str| s.rsplit('-').next().and_then(|p| p.parse::<u32>().ok());
    let (Some(pid), Some(base_pid)) = (pid_of(name), pid_of(base)) else {
        return false;
    };
    if !base.ends_with(&format!("-{host}-{base_pid}")) || !Path::new("/proc/self").exists() {
        return false;
    }
    let gone = |p: u32| !Path::new("/proc").join(p.to_string()).exists();
    gone(pid) && gone(base_pid)
}
