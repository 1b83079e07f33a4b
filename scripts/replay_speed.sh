#!/usr/bin/env bash
# Replay speed side by side, on one MRCLAM robot (default: robot 3 of
# dataset 6): the pure-Python reference (scripts/replay_speed.py: loading,
# then a scalar 3-state EKF loop), Locus's replay engine (the example
# `replay_speed`: loading, the 7-state filter with evaluation, and with the
# smoother) and the whole `locus replay` command (with and without its
# estimate of the odometry delay). Prints microseconds per event and the
# ratios. Times are wall clock on this machine, best of several runs for
# the engine; run it on an idle machine.
#
#   bash scripts/replay_speed.sh [DATASET_DIR] [ROBOT]
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-../shared/data/mrclam/MRCLAM_Dataset6}
ROBOT=${2:-3}
cargo build --release -q -p locus
cargo build --release -q -p locus-replay --example replay_speed
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
python3 scripts/replay_speed.py "$DIR" --robot "$ROBOT" > "$OUT/python.json"
target/release/examples/replay_speed "$DIR" "$ROBOT" > "$OUT/engine.json"
best() { # best wall time of 3 runs of the command, s
  local b=
  for _ in 1 2 3; do
    local s e
    s=$(date +%s.%N)
    "$@" > /dev/null
    e=$(date +%s.%N)
    b=$(python3 -c "import sys; t=$e-$s; b='$b'; print(min(t, float(b)) if b else t)")
  done
  echo "$b"
}
CMD=$(best target/release/locus replay mrclam "$DIR" --robot "$ROBOT" --no-plots --out "$OUT/r")
CMD_PLAIN=$(best target/release/locus replay mrclam "$DIR" --robot "$ROBOT" --no-plots --no-estimate --out "$OUT/r")
python3 - "$OUT/python.json" "$OUT/engine.json" "$CMD" "$CMD_PLAIN" <<'PY'
import json, sys
py = json.load(open(sys.argv[1])); en = json.load(open(sys.argv[2]))
cmd, plain = float(sys.argv[3]), float(sys.argv[4])
n = py["events"]
py_loop = py["filter_us_per_event"]; py_all = (py["load_s"] + py["filter_s"]) / n * 1e6
rows = [
    ("Python: filter loop (3 states)", py_loop, None),
    ("Python: load + filter loop", py_all, None),
    ("Locus engine: 7-state filter + evaluation", en["filter_us_per_event"], py_loop),
    ("Locus engine: filter + smoother + evaluation", en["filter_smoother_us_per_event"], py_loop),
    ("locus replay --no-estimate (load, filter, log.csv, tables)", plain / n * 1e6, py_all),
    ("locus replay (also estimates the odometry delay: 8 more filter runs)", cmd / n * 1e6, py_all),
]
print(f"robot {py['robot']}: {n} events")
print(f"| what | us per event | Python's time / this |")
print(f"|---|---|---|")
for name, us, ref in rows:
    ratio = f"{ref / us:.1f}x" if ref else "-"
    print(f"| {name} | {us:.2f} | {ratio} |")
PY
