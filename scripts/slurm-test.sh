#!/usr/bin/env bash
# Sweeps on a real Slurm: starts a single-node Slurm on this machine from Debian's
# slurm-wlm and munge (munged, slurmctld and slurmd as root, every address 127.0.0.1, no cgroups:
# ProctrackType=proctrack/linuxproc, TaskPlugin=task/none), plans a 2 x 2 x 3-seed sweep of
# short arena runs, submits its sweep.sbatch with the real sbatch (a job array of 6 tasks of 2
# points), waits for it, merges it, and checks:
#   1. every array task COMPLETED with exit code 0, and every point finished;
#   2. the merged table (sweep.csv and sweep.json) and every point's files (run.txt, the
#      console text with its wall time, aside) are byte-identical to the same sweep run on this
#      machine by `h8swarm sweep run DIR --task I` for each task in a loop;
#   3. after a point folder is deleted, another is broken and a killed task's temporary folder
#      is left behind, submitting the same script again redoes exactly those two points, skips
#      the other ten, removes the leftover, and merges to the same table.
#
#   scripts/slurm-test.sh             (as root; H8SWARM_BIN=path picks the binary, default:
#                                      cargo build --release --bin h8swarm: the build the tests
#                                      use; KEEP=1 keeps the Slurm folder)
#
# Needs: apt-get install slurm-wlm munge. About 30 s on a 2-core machine with that build
# (the points are short: 0.7 s each); CI runs it after the tests (.ci/run). The daemons are
# stopped at any exit (an error, a failed check, Ctrl-C, `timeout`), by the pids they wrote.
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)
say() { printf '[slurm-test %3ss] %s\n' "$(($(date +%s) - started))" "$*"; }
fail() { say "FAILED: $*"; exit 1; }

[ "$(id -u)" -eq 0 ] || fail "run as root (slurmd starts jobs as their user; here every daemon is root)"
for c in munged slurmctld slurmd sbatch squeue scontrol sinfo; do
    command -v "$c" >/dev/null || fail "$c not found: apt-get install slurm-wlm munge"
done

if [ -n "${H8SWARM_BIN:-}" ]; then
    bin=$(realpath "$H8SWARM_BIN")
else
    cargo build --locked --quiet --release --bin h8swarm
    bin=$(realpath "${CARGO_TARGET_DIR:-target}")/release/h8swarm
fi
[ -x "$bin" ] || fail "no h8swarm binary at $bin"

state=$(mktemp -d /tmp/h8swarm-slurm.XXXXXX)
chmod 755 "$state"
job=""
cleanup() {
    status=$?
    if [ -n "$job" ]; then scancel "$job" 2>/dev/null || true; fi
    # Only the daemons this script started, by the pids they wrote.
    for d in slurmd slurmctld munged; do
        if [ -s "$state/$d.pid" ]; then
            pid=$(cat "$state/$d.pid")
            kill "$pid" 2>/dev/null || true
            # Let it write its last state before the folder goes.
            for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
        fi
    done
    if [ "$status" -ne 0 ]; then
        for log in slurmctld.log slurmd.log munged.log; do
            [ -f "$state/$log" ] && { echo "--- $log (last lines)"; tail -n 15 "$state/$log"; }
        done
        for log in "$state"/slurm-run/logs/*.out; do
            [ -f "$log" ] && { echo "--- $(basename "$log")"; tail -n 5 "$log"; }
        done
    fi
    if [ "${KEEP:-0}" = 1 ]; then say "kept $state"; else rm -rf "$state" || true; fi
}
trap cleanup EXIT
# A signal ends the script through the EXIT trap too (bash alone would not run it on TERM).
trap 'fail "interrupted"' INT TERM HUP
# A command that fails outside the checks (set -e) says which line.
trap 'fail "line $LINENO: \`$BASH_COMMAND\` failed"' ERR

# Two free loopback ports for slurmctld and slurmd.
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
ports=()
for p in $(seq 16817 16899); do
    if port_free "$p"; then ports+=("$p"); fi
    [ "${#ports[@]}" -ge 2 ] && break
done
[ "${#ports[@]}" -ge 2 ] || fail "no two free ports in 16817-16899"

say "munge: a fresh key, munged on $state/munge.sock"
dd if=/dev/urandom of="$state/munge.key" bs=1024 count=1 status=none
chmod 600 "$state/munge.key"
munged --force --socket="$state/munge.sock" --key-file="$state/munge.key" \
    --log-file="$state/munged.log" --pid-file="$state/munged.pid" --seed-file="$state/munged.seed"

mem_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2))
cpus=$(nproc)
mkdir -p "$state/ctld" "$state/d"
cat >"$state/slurm.conf" <<EOF
ClusterName=h8swarm-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=${ports[0]}
SlurmdPort=${ports[1]}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$state/munge.sock
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/d
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MpiDefault=none
ReturnToService=2
MinJobAge=3600
NodeName=h8node NodeAddr=127.0.0.1 NodeHostname=$(hostname) CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=h8test Nodes=h8node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$state/slurm.conf
say "slurmctld on 127.0.0.1:${ports[0]}, slurmd (node h8node: $cpus CPUs, $mem_mb MB) on :${ports[1]}"
slurmctld -f "$SLURM_CONF" -c
slurmd -f "$SLURM_CONF" -N h8node
for _ in $(seq 1 60); do
    [ "$(sinfo -h -n h8node -o %t 2>/dev/null)" = idle ] && break
    sleep 1
done
[ "$(sinfo -h -n h8node -o %t)" = idle ] || fail "node h8node is not idle: $(sinfo -h -n h8node -o '%t %E')"

cat >"$state/sweep.toml" <<'EOF'
# The test sweep: 2 x 2 x 3 seeds of short arena runs.
name = "slurm-test"
base = "arena"
seeds = [1, 2, 3]

[set]
steps = 120
window = 40
repeats = 2

[grid]
"learner.eta" = [0.001, 0.01]
"learner.history" = [0, 1]

[slurm]
points_per_task = 2
max_parallel = 2
max_cpus = 1
EOF
"$bin" sweep plan "$state/sweep.toml" --out "$state/slurm-run" --bin "$bin" >/dev/null
"$bin" sweep plan "$state/sweep.toml" --out "$state/local-run" --bin "$bin" >/dev/null
tasks=$(sed -n 's/^  "tasks": \([0-9]*\),$/\1/p' "$state/slurm-run/plan.json")
[ "$tasks" = 6 ] || fail "the plan has $tasks tasks, expected 6"
grep -q '^#SBATCH --array=0-5%2$' "$state/slurm-run/sweep.sbatch" || fail "sweep.sbatch lacks --array=0-5%2"

# Waits for job $1 to leave the queue, then checks that every array task completed.
wait_job() {
    local j=$1 t0
    t0=$(date +%s)
    while [ -n "$(squeue -h -j "$j" 2>/dev/null)" ]; do
        [ $(($(date +%s) - t0)) -lt 300 ] || fail "job $j still queued after 300 s: $(squeue -j "$j")"
        sleep 1
    done
    local states
    states=$(scontrol -o show job "$j" | grep -o 'JobState=[A-Z]* .*ExitCode=[0-9:]*' |
        sed 's/ .*ExitCode=/ /' | sort | uniq -c)
    say "job $j: $(echo "$states" | tr '\n' ';')"
    [ "$(scontrol -o show job "$j" | grep -c 'JobState=COMPLETED .*ExitCode=0:0')" = "$tasks" ] ||
        fail "not every one of the $tasks array tasks of job $j completed with exit code 0"
}

say "sbatch $state/slurm-run/sweep.sbatch"
job=$(sbatch --parsable "$state/slurm-run/sweep.sbatch")
job=${job%%;*}
wait_job "$job"
slurm_done=$(date +%s)

say "the same sweep here: h8swarm sweep run DIR --task I, I = 0..$((tasks - 1))"
for i in $(seq 0 $((tasks - 1))); do
    "$bin" sweep run "$state/local-run" --task "$i" --threads 1 >/dev/null 2>&1 ||
        fail "local task $i failed"
done
local_done=$(date +%s)

"$bin" sweep merge "$state/slurm-run" --require-complete >"$state/merge-slurm.txt"
"$bin" sweep merge "$state/local-run" --require-complete >"$state/merge-local.txt"
for f in sweep.csv sweep.json; do
    cmp "$state/slurm-run/merged/$f" "$state/local-run/merged/$f" ||
        fail "merged/$f differs between the Slurm run and the local run"
done
diff -r --exclude=run.txt "$state/slurm-run/points" "$state/local-run/points" >/dev/null ||
    fail "the points' files differ between the Slurm run and the local run"
rows=$(($(wc -l <"$state/slurm-run/merged/sweep.csv") - 1))
cols=$(head -n 1 "$state/slurm-run/merged/sweep.csv" | tr ',' '\n' | wc -l)
oks=$(grep -c ',ok,' "$state/slurm-run/merged/sweep.csv" || true)
[ "$rows" = 12 ] && [ "$oks" = 12 ] || fail "the table has $rows rows, $oks ok; expected 12 and 12"
say "identical: merged/sweep.csv ($rows rows x $cols columns), sweep.json and every point's files"

say "preemption: one point deleted, one broken, a killed task's folder left; sbatch again"
pts=$state/slurm-run/points
first=$(sed -n '6p' "$state/slurm-run/points.jsonl" | sed 's/.*"id":"\([^"]*\)".*/\1/')
second=$(sed -n '9p' "$state/slurm-run/points.jsonl" | sed 's/.*"id":"\([^"]*\)".*/\1/')
rm -rf "${pts:?}/$first"
rm -f "$pts/$second/status.json"
mkdir -p "$pts/.tmp-$second-deadhost-1" && echo partial >"$pts/.tmp-$second-deadhost-1/metrics.csv"
"$bin" sweep merge "$state/slurm-run" >"$state/merge-partial.txt"
grep -q "^MISSING $first" "$state/merge-partial.txt" || fail "merge does not list $first as missing"
grep -q "^BROKEN  $second" "$state/merge-partial.txt" || fail "merge does not list $second as broken"
job=$(sbatch --parsable "$state/slurm-run/sweep.sbatch")
job=${job%%;*}
wait_job "$job"
ran=$(cat "$state"/slurm-run/logs/"${job}"_*.out | grep -c ' done in ' || true)
skipped=$(cat "$state"/slurm-run/logs/"${job}"_*.out | grep -c 'finished before: skipped' || true)
[ "$ran" = 2 ] && [ "$skipped" = 10 ] || fail "the resubmission ran $ran points and skipped $skipped; expected 2 and 10"
[ ! -e "$pts/.tmp-$second-deadhost-1" ] || fail "the killed task's temporary folder is still there"
"$bin" sweep merge "$state/slurm-run" --require-complete >/dev/null
cmp "$state/slurm-run/merged/sweep.csv" "$state/local-run/merged/sweep.csv" ||
    fail "the table after the resubmission differs"
diff -r --exclude=run.txt "$state/slurm-run/points" "$state/local-run/points" >/dev/null ||
    fail "the points' files after the resubmission differ"
say "the resubmission redid 2 points, skipped 10, and merged to the same table"

job=""
say "passed: Slurm array $((slurm_done - started)) s from start, local loop $((local_done - slurm_done)) s, total $(($(date +%s) - started)) s"
