//! The memory a run needs, checked before it starts against what the machine has and what
//! the kernel allows this process: `--max-memory`, the available memory, a control group's
//! room (Slurm's `--mem`) and the address-space limit (`ulimit -v`).

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use swarm::scenario::Scenario;

/// Host memory one robot takes while its run is going, with a margin (measured, see
/// docs/performance.md: the peak resident size of `h8swarm run --robots 10000` less that of
/// 1 000 robots, per robot: model robots 16 KB; firmware robots 39 KB, the flash and the
/// CPU's decoded code being shared).
pub const MODEL_ROBOT_BYTES: u64 = 24 << 10;

/// See [`MODEL_ROBOT_BYTES`].
pub const FIRMWARE_ROBOT_BYTES: u64 = 56 << 10;

/// Host memory per window of a run kept for the summary and the plots (the window's sums;
/// the steps themselves are written as they complete and not kept), with a margin.
pub const WINDOW_BYTES: u64 = 128;

/// The tool itself (code, fonts, the fit, the plots), with a margin.
pub const BASE_BYTES: u64 = 64 << 20;

/// The memory a run of `s` on `threads` threads is estimated to need: the runs going at once
/// (one per thread) with their robots, and every run's metrics.
#[must_use]
pub fn estimated_memory(s: &Scenario, threads: usize) -> u64 {
    let (runs, at_once) = run_counts(s, threads);
    let per_robot = match s.controller.kind {
        swarm::scenario::ControllerKind::Firmware => FIRMWARE_ROBOT_BYTES,
        swarm::scenario::ControllerKind::Model => MODEL_ROBOT_BYTES,
    };
    BASE_BYTES
        .saturating_add(
            at_once
                .saturating_mul(s.robots as u64)
                .saturating_mul(per_robot),
        )
        .saturating_add(
            runs.saturating_mul(u64::from(s.steps / s.window.max(1)) + 1)
                .saturating_mul(WINDOW_BYTES),
        )
}

/// The runs of `s` (conditions × repeats) and how many of them go at once on `threads`.
fn run_counts(s: &Scenario, threads: usize) -> (u64, u64) {
    let conditions = 1 + u64::from(s.controls.learning_off) + u64::from(s.controls.random_walk);
    let runs = conditions.saturating_mul(u64::from(s.repeats));
    (runs, runs.min(threads as u64).max(1))
}

/// The memory the machine has available now (`MemAvailable` of /proc/meminfo), if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// Address space a run takes beyond the memory it uses: the program's own mappings and
/// thread stacks, and the allocator's reservations (an arena of 64 MiB a thread at most).
/// Only compared with an address-space limit (`ulimit -v`), which counts reservations too.
pub const ADDRESS_SPACE_BASE_BYTES: u64 = 192 << 20;

/// See [`ADDRESS_SPACE_BASE_BYTES`]: per worker thread.
pub const ADDRESS_SPACE_PER_THREAD_BYTES: u64 = 66 << 20;

/// The limits the kernel holds this process to, besides the machine's memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProcessLimits {
    /// The soft address-space limit (`ulimit -v`, RLIMIT_AS), bytes.
    pub address_space: Option<u64>,
    /// What the process's control groups still let it use: the least, over its cgroup and
    /// every cgroup above it, of the limit less the usage (cgroup v2 `memory.max` less
    /// `memory.current`, or v1 `memory.limit_in_bytes` less `memory.usage_in_bytes`). Slurm's
    /// `--mem` is such a limit.
    pub cgroup_room: Option<u64>,
}

impl ProcessLimits {
    /// This process's limits, from /proc/self/limits, /proc/self/cgroup and /sys/fs/cgroup
    /// (none where they cannot be read: another system, or no limit).
    #[must_use]
    pub fn read() -> ProcessLimits {
        let limits = std::fs::read_to_string("/proc/self/limits").unwrap_or_default();
        let cgroups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
        ProcessLimits {
            address_space: address_space_limit(&limits),
            cgroup_room: cgroup_room(Path::new("/sys/fs/cgroup"), &cgroups),
        }
    }
}

/// The soft "Max address space" of a /proc/PID/limits text (`None`: unlimited or absent).
#[must_use]
pub fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The memory the control groups of a /proc/PID/cgroup text still allow, read under `root`
/// (normally /sys/fs/cgroup): v2 (`0::PATH`, `memory.max` and `memory.current`, also under
/// `unified/` on hybrid systems) and v1 (`N:memory:PATH` or `N:…,memory,…:PATH`,
/// `memory/…/memory.limit_in_bytes` and `memory.usage_in_bytes`), each cgroup from the
/// process's own up to the root; a cgroup path the mount does not show is looked up from the
/// mount's root (a container sees its own cgroup there). `None` when no limit is found.
#[must_use]
pub fn cgroup_room(root: &Path, cgroups: &str) -> Option<u64> {
    let read = |p: PathBuf| -> Option<u64> {
        let t = std::fs::read_to_string(p).ok()?;
        t.trim().parse().ok()
    };
    let mut room: Option<u64> = None;
    let mut consider = |limit: Option<u64>, used: Option<u64>| {
        // v1 writes "no limit" as a huge number near 2^63.
        if let Some(limit) = limit.filter(|&l| l < 1 << 60) {
            let left = limit.saturating_sub(used.unwrap_or(0));
            room = Some(room.map_or(left, |r| r.min(left)));
        }
    };
    for line in cgroups.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (bases, max_file, used_file): (Vec<PathBuf>, &str, &str) = if controllers.is_empty() {
            (
                vec![root.to_path_buf(), root.join("unified")],
                "memory.max",
                "memory.current",
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                vec![root.join("memory")],
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        for base in bases {
            let own = base.join(path.trim_start_matches('/'));
            let start = if own.is_dir() { own } else { base.clone() };
            let mut dir = Some(start.as_path());
            while let Some(d) = dir {
                if !d.starts_with(&base) {
                    break;
                }
                consider(read(d.join(max_file)), read(d.join(used_file)));
                dir = d.parent();
            }
        }
    }
    room
}

/// Refuses a run estimated to need more than `max` (default: the available memory), or than
/// the process's own limits allow ([`ProcessLimits`]: a cgroup's room, and for the address
/// space the need with [`ADDRESS_SPACE_BASE_BYTES`] and [`ADDRESS_SPACE_PER_THREAD_BYTES`]);
/// `extra` is memory the run holds besides the estimate (a pin trace's buffers).
pub(crate) fn check_memory(
    s: &Scenario,
    threads: usize,
    max: Option<u64>,
    extra: u64,
) -> Result<()> {
    check_memory_within(s, threads, max, extra, &ProcessLimits::read())
}

fn check_memory_within(
    s: &Scenario,
    threads: usize,
    max: Option<u64>,
    extra: u64,
    limits: &ProcessLimits,
) -> Result<()> {
    let need = estimated_memory(s, threads).saturating_add(extra);
    let address_space = need
        .saturating_add(ADDRESS_SPACE_BASE_BYTES)
        .saturating_add((threads as u64).saturating_mul(ADDRESS_SPACE_PER_THREAD_BYTES));
    let machine = max.or_else(available_memory);
    let refusal = if let Some(limit) = machine.filter(|&l| need > l) {
        Some((
            need,
            if max.is_some() {
                "--max-memory"
            } else {
                "the memory available on this machine"
            },
            limit,
            "raise --max-memory",
        ))
    } else if let Some(room) = limits.cgroup_room.filter(|&r| need > r) {
        Some((
            need,
            "the memory its control group still allows (cgroup memory.max, as Slurm's --mem sets it)",
            room,
            "ask for more memory (Slurm: --mem)",
        ))
    } else {
        limits
            .address_space
            .filter(|&l| address_space > l)
            .map(|l| {
                (
                    address_space,
                    "the address-space limit of this process (ulimit -v)",
                    l,
                    "raise ulimit -v",
                )
            })
    };
    if let Some((need, what, limit, raise)) = refusal {
        let (runs, at_once) = run_counts(s, threads);
        let with_space = if need == address_space {
            format!(
                " of address space (with {} for the program and {} a thread)",
                show_bytes(ADDRESS_SPACE_BASE_BYTES),
                show_bytes(ADDRESS_SPACE_PER_THREAD_BYTES)
            )
        } else {
            " of memory".to_string()
        };
        bail!(
            "this run needs about {}{with_space} ({} robots x {at_once} runs at once, {} steps x {runs} runs of metrics{}) but {what} is {}: use fewer robots, threads, steps or repeats, or {raise}",
            show_bytes(need),
            s.robots,
            s.steps,
            if extra > 0 {
                format!(", {} of pin-trace buffers", show_bytes(extra))
            } else {
                String::new()
            },
            show_bytes(limit)
        );
    }
    Ok(())
}

/// A size for a message: bytes below 1 KiB, else KiB, MiB or GiB with one decimal (never
/// "0 MiB" for a size that is not 0).
#[must_use]
pub fn show_bytes(b: u64) -> String {
    const UNITS: [(u32, &str); 3] = [(30, "GiB"), (20, "MiB"), (10, "KiB")];
    for (shift, unit) in UNITS {
        if b >= 1 << shift {
            return format!("{:.1} {unit}", b as f64 / (1u64 << shift) as f64);
        }
    }
    format!("{b} bytes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_grow_with_the_run() {
        let s = Scenario::arena();
        let one = estimated_memory(&s, 1);
        assert!(estimated_memory(&s, 2) > one);
        let big = s
            .clone()
            .with_overrides(Some(100_000), None, None, None)
            .unwrap();
        // 100 000 model robots on one thread: about 2.3 GiB (24 KiB a robot), under 4 GiB.
        let e = estimated_memory(&big, 1);
        assert!(e > 2 << 30 && e < 3 << 30, "{e}");
        assert!(check_memory(&big, 1, Some(2 << 30), 0).is_err());
        assert!(check_memory(&big, 1, Some(4 << 30), 0).is_ok());
        assert!(check_memory(&s, 1, Some(8 << 30), 0).is_ok());
    }

    #[test]
    fn sizes_in_messages_are_never_rounded_to_nothing() {
        assert_eq!(show_bytes(1), "1 bytes");
        assert_eq!(show_bytes(1023), "1023 bytes");
        assert_eq!(show_bytes(1024), "1.0 KiB");
        assert_eq!(show_bytes(1536), "1.5 KiB");
        assert_eq!(show_bytes(64 << 20), "64.0 MiB");
        assert_eq!(show_bytes(22 << 30), "22.0 GiB");
        let e = check_memory(&Scenario::arena(), 1, Some(1024), 0).unwrap_err();
        assert!(e.to_string().contains("--max-memory is 1.0 KiB"), "{e}");
    }

    #[test]
    fn the_process_limits_are_read_and_checked() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\nMax data size             unlimited            unlimited            bytes\nMax address space         4096000000           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(4_096_000_000));
        assert_eq!(
            address_space_limit("Max address space  unlimited  unlimited  bytes\n"),
            None
        );
        // A fake cgroup tree: v2 with a limit on a parent, v1 with its own.
        let root = std::env::temp_dir().join(format!("h8swarm-cgroups-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let job = root.join("slurm/job_7/step_0");
        std::fs::create_dir_all(&job).unwrap();
        std::fs::write(root.join("slurm/job_7/memory.max"), "1073741824\n").unwrap();
        std::fs::write(root.join("slurm/job_7/memory.current"), "73741824\n").unwrap();
        std::fs::write(job.join("memory.max"), "max\n").unwrap();
        assert_eq!(
            cgroup_room(&root, "0::/slurm/job_7/step_0\n"),
            Some(1_000_000_000)
        );
        assert_eq!(cgroup_room(&root, "0::/elsewhere\n"), None);
        let v1 = root.join("memory/job");
        std::fs::create_dir_all(&v1).unwrap();
        std::fs::write(v1.join("memory.limit_in_bytes"), "536870912\n").unwrap();
        std::fs::write(v1.join("memory.usage_in_bytes"), "36870912\n").unwrap();
        std::fs::write(
            root.join("memory/memory.limit_in_bytes"),
            "9223372036854771712\n",
        )
        .unwrap();
        assert_eq!(cgroup_room(&root, "4:memory:/job\n"), Some(500_000_000));
        let _ = std::fs::remove_dir_all(&root);
        // The checks: a cgroup's room, then the address space.
        let s = Scenario::arena();
        let roomy = ProcessLimits::default();
        assert!(check_memory_within(&s, 2, Some(1 << 40), 0, &roomy).is_ok());
        let tight = ProcessLimits {
            cgroup_room: Some(10 << 20),
            address_space: None,
        };
        let e = check_memory_within(&s, 2, Some(1 << 40), 0, &tight).unwrap_err();
        assert!(e.to_string().contains("control group"), "{e}");
        let small_as = ProcessLimits {
            cgroup_room: None,
            address_space: Some(200 << 20),
        };
        let e = check_memory_within(&s, 2, Some(1 << 40), 0, &small_as).unwrap_err();
        assert!(e.to_string().contains("ulimit -v"), "{e}");
    }
}
