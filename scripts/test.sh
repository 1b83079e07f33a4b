#!/usr/bin/env bash
# Runs every test of Locus, and first installs what the tests need when it is
# missing: rustfmt/clippy, the thumbv7em-none-eabihf target (the core must
# build for a Cortex-M4F), and the pinned Python packages of the filterpy
# cross-check (scripts/requirements-crosscheck.txt) and of the Python
# package's tests (python/requirements-test.txt: pytest, Dask, nbclient).
# The firmware (firmware/, its own workspace) also needs qemu-system-arm
# (Debian's package; installed with apt-get when missing) and rustup's
# llvm-tools (llvm-nm for the footprint).
# Also Debian's chromium and chromium-driver for the teaching UI's
# end-to-end tests (crates/locus-serve/tests/e2e.rs), and iverilog and
# verilator for the Verilog correction core (hdl/; apt-get, sudo if not
# root).
set -euo pipefail
cd "$(dirname "$0")/.."

START=$(date +%s)
step() { printf '\n== %s (at %d s)\n' "$*" "$(($(date +%s) - START))"; }

# A full run is one-shot: incremental caches would only cost disk (over 1 GB
# for the optimised test profile). A developer may set CARGO_INCREMENTAL=1.
export CARGO_INCREMENTAL=${CARGO_INCREMENTAL:-0}
TARGET_DIR=${CARGO_TARGET_DIR:-target}
disk() { df -h . | awk 'NR == 2 { printf "disk: %s free of %s\n", $4, $2 }'; }
disk

step "toolchain: rustfmt, clippy, thumbv7em-none-eabihf"
installed_components=$(rustup component list --installed 2>/dev/null || true)
for c in rustfmt clippy; do
  grep -q "^$c" <<<"$installed_components" || rustup component add "$c"
done
rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf

step "firmware tools: qemu-system-arm (mps2-an386), llvm-tools"
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; fi
  $SUDO apt-get update
  $SUDO apt-get install -y qemu-system-arm
fi
grep -q "^llvm-tools" <<<"$installed_components" || rustup component add llvm-tools
HOST_TRIPLE=$(rustc -vV | sed -n 's/^host: //p')

step "hardware simulators: Icarus Verilog and Verilator (the Verilog correction core, hdl/)"
if ! command -v iverilog >/dev/null 2>&1 || ! command -v verilator >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y iverilog verilator
fi

step "python: the filterpy cross-check's and the Python package's test requirements"
PY=${LOCUS_PYTHON:-python3}
for req in scripts/requirements-crosscheck.txt python/requirements-test.txt; do
  if ! REQ="$req" "$PY" - <<'PYEOF' 2>/dev/null
import importlib.metadata as m, os, pathlib, sys
want = [l.split("==") for l in pathlib.Path(os.environ["REQ"]).read_text().split() if "==" in l]
sys.exit(0 if all(m.version(n) == v for n, v in want) else 1)
PYEOF
  then
    "$PY" -m pip install --quiet -r "$req"
  fi
done

step "browser: chromium and chromium-driver (teaching UI end-to-end tests)"
if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y chromium chromium-driver
fi

step "format"
cargo fmt --all -- --check

step "clippy (-D warnings)"
cargo clippy --workspace --all-targets --locked -- -D warnings

step "docs (-D warnings)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace --locked

step "no_std build for thumbv7em-none-eabihf"
cargo build --locked -p locus-core -p locus-models -p locus-odometry -p locus-control -p locus-link --no-default-features --target thumbv7em-none-eabihf

step "teaching UI: vendored chart library against the npm lock (when npm is present)"
# The build never needs npm (uPlot is vendored); with npm the test also
# compares the vendored files with the package npm installs from the lock.
if command -v npm >/dev/null 2>&1; then
  (cd crates/locus-serve/web && npm ci --no-audit --no-fund --silent) || echo "npm ci failed (offline?): checking the recorded hashes only"
fi

step "tests (optimised test profile)"
cargo test --workspace --locked

step "regression guards: byte-identical run and replay logs (scripts/regression-guards.sha256)"
bash scripts/regression_guards.sh

step "benchmarks compile (in the test profile: the tests' build is shared)"
cargo test --workspace --locked --benches --no-run

step "firmware: format, clippy (thumbv7em-none-eabihf and host), docs"
(cd firmware && cargo fmt --all -- --check)
(cd firmware && cargo clippy --locked --release -p locus-fw -p locus-fw-app -- -D warnings)
(cd firmware && cargo clippy --locked --target "$HOST_TRIPLE" -p locus-fw-app --all-targets -- -D warnings)
(cd firmware && RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --locked)

step "firmware: under QEMU mps2-an386, bit-identical to the host f32 run; footprint; instructions per step"
(cd firmware && cargo test --locked --target "$HOST_TRIPLE" -p locus-fw-app -- --nocapture)

echo
disk
du -sh "$TARGET_DIR" firmware/target 2>/dev/null || true
echo "all tests passed in $(($(date +%s) - START)) s"
