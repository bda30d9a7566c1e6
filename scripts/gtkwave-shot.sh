#!/usr/bin/env bash
# gtkwave-shot.sh - a GTKWave screenshot of one robot firmware step with an EEPROM save, for
# docs/debugging.md (docs/gtkwave-step.png), made under Xvfb. Not part of CI.
#
#   scripts/gtkwave-shot.sh [OUT.png]
#
# Runs `h8swarm run arena --controller firmware` (3 robots, 21 steps, one repeat) with
# `--vcd --vcd-robot 0 --vcd-from 19 --vcd-steps 1`: step 19 is the arena's first save
# (learner.save_every = 20). GTKWave opens the trace with every signal and the phase, zoomed
# from the step's A/D start to the end of its I2C traffic; Xvfb keeps its screen as an X window
# dump (-fbdir), which scripts/xwd2png.py turns into a PNG. Needs Debian's gtkwave and xvfb.
set -euo pipefail
export LC_ALL=C

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out_png="${1:-docs/gtkwave-step.png}"
for tool in gtkwave Xvfb python3; do
  if ! command -v "$tool" >/dev/null; then
    echo "gtkwave-shot.sh: '$tool' not found; install Debian's gtkwave and xvfb" >&2
    exit 2
  fi
done
work="$root/target/gtkwave-shot"
rm -rf "$work"
mkdir -p "$work/fb" "$(dirname "$out_png")"

echo "== tracing step 19 of robot 0 (arena, firmware)"
cargo build --release --locked --bin h8swarm >/dev/null
h8swarm="${CARGO_TARGET_DIR:-$root/target}/release/h8swarm"
"$h8swarm" run arena --controller firmware --robots 3 --steps 21 --repeats 1 \
  --out "$work/run" --vcd "$work/step.vcd" --vcd-robot 0 --vcd-from 19 --vcd-steps 1 >/dev/null

# The zoom: from 0.2 ms before the step's ADST rise to 0.5 ms after its last SCL edge, in ns
# (GTKWave's unit for a trace whose timescale is 10 ns).
read -r from to < <(python3 - "$work/step.vcd" <<'PY'
import sys
units = {"fs": 1e-6, "ps": 1e-3, "ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
ids, t, adst, scl, ns = {}, 0, None, None, None
for line in open(sys.argv[1]):
    w = line.split()
    if line.startswith("$timescale"):
        ns = int(w[1]) * units[w[2]]
    elif line.startswith("$var"):
        ids[w[3]] = w[4]
    elif line.startswith("#"):
        t = int(line[1:])
    elif line[:1] in "01" and len(line.strip()) >= 2:
        name = ids.get(line.strip()[1:])
        if name == "ADST" and line[0] == "1" and adst is None:
            adst = t
        if name == "SCL" and adst is not None:
            scl = t
if adst is None or scl is None or ns is None:
    sys.exit("gtkwave-shot.sh: no timescale, no A/D start or no I2C traffic in the traced step")
print(int(adst * ns) - 200_000, int(scl * ns) + 500_000)
PY
)
echo "== zoom: $from ns to $to ns"

cat >"$work/view.gtkw" <<GTKW
[dumpfile] "$work/step.vcd"
[size] 1400 560
[pos] 0 0
[signals_width] 170
[sst_expanded] 0
[sst_width] 1
@28
h8_3052f.TIOCA1
h8_3052f.TIOCA2
h8_3052f.PB0
h8_3052f.PB1
h8_3052f.PB2
h8_3052f.PB3
h8_3052f.SDA
h8_3052f.SCL
h8_3052f.ADST
h8_3052f.ADF
h8_3052f.IMIA0
h8_3052f.SLEEP
firmware.phase
GTKW
cat >"$work/zoom.tcl" <<TCL
gtkwave::setZoomRangeTimes $from $to
TCL

display=":$((90 + RANDOM % 100))"
Xvfb "$display" -screen 0 1400x560x24 -fbdir "$work/fb" -nolisten tcp >"$work/xvfb.log" 2>&1 &
xvfb_pid=$!
gtk_pid=""
cleanup() {
  [ -n "$gtk_pid" ] && kill "$gtk_pid" 2>/dev/null || true
  kill "$xvfb_pid" 2>/dev/null || true
}
trap cleanup EXIT
sleep 2
DISPLAY="$display" gtkwave -S "$work/zoom.tcl" "$work/step.vcd" "$work/view.gtkw" \
  >"$work/gtkwave.log" 2>&1 &
gtk_pid=$!
sleep 8
python3 "$root/scripts/xwd2png.py" "$work/fb/Xvfb_screen0" "$out_png"
echo "== wrote $out_png"
