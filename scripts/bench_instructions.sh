#!/usr/bin/env bash
# Instructions executed per EKF step, for each variant of the ekf_step bench
# (crates/locus-core/benches/ekf_step.rs): a load-independent figure to read
# next to the bench's time ratios.
#
# Each variant is run N and 2N times in the bench binary itself
# (EKF_STEP_RUN=<variant>:<n>[:chained], which skips criterion) under
# `valgrind --tool=callgrind`; instructions per step = (I(2N) - I(N)) / N, so
# start-up and the agreement checks cancel. libm's sin_cos counts (it is part
# of the step). This counts instructions, not time: the same count can run at
# different speeds (dependency chains, scheduler pressure), so it supports the
# interleaved timings and does not replace them.
#
#     scripts/bench_instructions.sh [N]        # default N = 100000
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-100000}
command -v valgrind > /dev/null || { echo "valgrind not found" >&2; exit 1; }

bin=$(cargo bench -p locus-core --bench ekf_step --no-run --message-format=json 2> /dev/null \
    | sed -n 's/.*"executable":"\([^"]*ekf_step[^"]*\)".*/\1/p' | tail -n 1)
[ -x "$bin" ] || { echo "ekf_step bench binary not found" >&2; exit 1; }

count() { # variant, n, mode -> instructions of the whole run
    EKF_STEP_RUN="$1:$2:$3" valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" 2>&1 \
        | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}

variants="closed_f64 nalgebra_f64 locus_plain_f64 locus_joseph_f64 user_plain_f64 builtin_user_f64 nalgebra_checked_f64 closed_f32 nalgebra_f32 locus_plain_f32 locus_joseph_f32 user_plain_f32 builtin_user_f32 nalgebra_checked_f32"
echo "Instructions per step (callgrind, (I(2N) - I(N)) / N, N = $n; $bin):"
for v in $variants; do
    a=$(count "$v" "$n" independent)
    b=$(count "$v" $((2 * n)) independent)
    echo "$v $(( (b - a) / n ))"
done | awk '
    { name[NR] = $1; ins[$1] = $2 }
    END {
        printf "%-20s %8s %9s %10s\n", "step/", "instr.", "x closed", "x nalgebra"
        for (k = 1; k <= NR; k++) {
            v = name[k]; p = (v ~ /f64$/) ? "f64" : "f32"
            printf "%-20s %8d %9.2f %10.2f\n", v, ins[v], ins[v] / ins["closed_" p], ins[v] / ins["nalgebra_" p]
        }
    }'
