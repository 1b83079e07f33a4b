#!/usr/bin/env bash
# Synthesises the Verilog correction core (hdl/core/ekf_core.v on the
# binary32 units of hdl/fp/) with Yosys for the papers' FPGA family,
# Cyclone IV E (synth_intel -family cycloneive: Yosys maps no DSP blocks
# there, so the multipliers become logic elements), and for Lattice ECP5
# (synth_ecp5: 18x18 multipliers in DSP blocks), and prints the logic
# cells, flip-flops, DSP multipliers and the longest combinational path
# (cells, Yosys's `ltp`; Yosys estimates no Fmax without place and route).
# Installs Debian's yosys when missing. Takes about 35 minutes on 2 cores.
# Usage: bash scripts/hw_synth.sh [OUT_DIR]   (default: target/hw-synth)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-target/hw-synth}
mkdir -p "$OUT"

if ! command -v yosys >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y yosys
fi

SOURCES="hdl/fp/fp_add.v hdl/fp/fp_mul.v hdl/fp/fp_div.v hdl/core/ekf_core.v"
run() {
  local name=$1 script=$2
  local start=$SECONDS
  yosys -q -l "$OUT/$name.log" -p "read_verilog -I hdl/fp $SOURCES; $script" >/dev/null 2>&1
  echo "$name: $((SECONDS - start)) s"
}
run cycloneive "synth_intel -family cycloneive -top ekf_core; tee -o $OUT/cycloneive.stat stat"
# Up to its `check` step: the `autoname` there had not finished after 10
# minutes on this design (Yosys 0.23).
run ecp5 "synth_ecp5 -top ekf_core -run begin:check; tee -o $OUT/ecp5.stat stat"
# Logic depth: Yosys's `ltp` needs its own flip-flop cells to cut paths at
# registers, so it runs on a generic 4-input-LUT mapping.
run depth "synth -flatten -top ekf_core; abc -lut 4; opt_clean; tee -o $OUT/depth.ltp ltp -noff"

count() { awk -v pat="$2" '$1 ~ pat { s += $2 } END { print s + 0 }' "$OUT/$1.stat"; }
depth=$(sed -n 's/.*Longest topological path in ekf_core (length=\([0-9]*\)).*/\1/p' "$OUT/depth.ltp" | tail -1)
printf '\n| target | logic | flip-flops | DSP multipliers |\n|---|---|---|---|\n'
printf '| Cyclone IV E (synth_intel) | %s LEs (cycloneive_lcell_comb) | %s | 0 (Yosys maps none) |\n' \
  "$(count cycloneive 'lcell_comb$')" "$(count cycloneive '^dffeas$')"
printf '| Lattice ECP5 (synth_ecp5) | %s LUT4 | %s | %s MULT18X18D |\n' \
  "$(count ecp5 '^LUT4$')" "$(count ecp5 '^TRELLIS_FF$')" "$(count ecp5 '^MULT18X18D$')"
printf '| papers 000/003 (Quartus II, EP4CE115) | 22 089 LEs | - | 175 (9x9) |\n'
printf '\nlongest register-to-register path: %s levels of 4-input LUTs (generic mapping; Yosys estimates no Fmax without place and route; paper: Fmax 49.08 MHz)\n' "$depth"
