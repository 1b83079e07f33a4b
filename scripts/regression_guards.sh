#!/usr/bin/env bash
# Regression guards: `locus run` at seed 1 writes a byte-identical log.csv for
# each built-in scenario, and `locus replay` of MRCLAM dataset 6 (robots 1-5)
# a byte-identical log.csv, against the SHA-256 sums recorded in
# scripts/regression-guards.sha256. A deliberate change that alters one is
# recorded there (with `--record`) and named in the commit.
#
#   bash scripts/regression_guards.sh            # check (exit 1 on a change)
#   bash scripts/regression_guards.sh --record   # rewrite the recorded sums
set -euo pipefail
cd "$(dirname "$0")/.."
SUMS=scripts/regression-guards.sha256
DATA=${LOCUS_MRCLAM:-../shared/data/mrclam/MRCLAM_Dataset6}
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
# The binary `cargo test --workspace` builds for the integration tests
# (test profile, optimised as release is, features unified with the
# tests'): after the tests, nothing is built again. Its logs are
# byte-identical to the release binary's (checked when the profile was
# chosen).
cargo test --workspace --locked --no-run --quiet >/dev/null
BIN=${CARGO_TARGET_DIR:-./target}/debug/locus
for s in square square-ideal wall45 tricycle-slip hover; do
  "$BIN" run "$s" --seed 1 --no-plots --out "$OUT/run-$s" >/dev/null
  echo "$(sha256sum < "$OUT/run-$s/log.csv" | cut -d' ' -f1)  run-$s"
done > "$OUT/sums"
if [ -d "$DATA" ]; then
  for r in 1 2 3 4 5; do
    "$BIN" replay mrclam "$DATA" --robot "$r" --no-plots --out "$OUT/replay-$r" >/dev/null
    echo "$(sha256sum < "$OUT/replay-$r/log.csv" | cut -d' ' -f1)  replay-mrclam6-robot-$r"
  done >> "$OUT/sums"
else
  echo "note: $DATA not found; the replay guards are skipped" >&2
fi
if [ "${1:-}" = "--record" ]; then
  cp "$OUT/sums" "$SUMS"
  echo "recorded $(wc -l < "$SUMS") sums in $SUMS"
  exit 0
fi
status=0
while read -r sum name; do
  want=$(awk -v n="$name" '$2 == n { print $1 }' "$SUMS")
  if [ "$sum" = "$want" ]; then
    echo "unchanged  $name"
  else
    echo "CHANGED    $name (recorded ${want:-none}, now $sum)"
    status=1
  fi
done < "$OUT/sums"
exit $status
