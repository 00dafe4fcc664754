#!/usr/bin/env bash
# Instructions per internal step of the SuperTwistingObserver model, counted
# by callgrind.
#
#   bench/perf/step_instructions.sh [STEPS]        (default 10000)
#
# Runs bench/perf/step_driver.c as CMake builds it with the observer's objects (the
# step_driver target of ./build.sh fmus: the FMUs' -O2, plus -g), for each configuration
#     valgrind --tool=callgrind --toggle-collect=fmi2DoStep step_driver CONFIG SCHEME STEPS
# i.e. counts the instructions executed inside the one fmi2DoStep (STEPS
# internal steps, plus one communication point) and divides by STEPS; the same
# for 2 STEPS gives the cost of the second STEPS alone (the steady state).  A
# second count (step_driver CONFIG SCHEME 1 STEPS: STEPS doSteps of H = h)
# gives the cost per step when every step is a communication point, as in
# the closed-loop harness; the same for 2 STEPS doSteps gives that cost in the
# steady state ("H=h then").
# Callgrind outputs stay in build/bench/callgrind.out.CONFIG-sSCHEME[-H=h]; inspect one with
#     callgrind_annotate --inclusive=yes build/bench/callgrind.out.joint-lsm-s1
#     callgrind_annotate --auto=yes build/bench/callgrind.out.joint-lsm-s1   (per source line)
# ONLY=REGEX runs the configurations whose "config|scheme" matches (ONLY='joint-lsm\|3').
# Other flags: configure a CMake tree of your own (e.g. -DCMAKE_C_FLAGS="-O3 -flto") and
# set STEP_DRIVER to its bin/step_driver (valgrind 3.19 cannot run AVX-512 code, so
# -march=native fails on such machines).
set -euo pipefail
cd "$(dirname "$0")/../.."

STEPS=${1:-10000}
OUT=build/bench
STEP_DRIVER=${STEP_DRIVER:-build/cmake/bin/step_driver}
command -v valgrind >/dev/null || { echo "step_instructions.sh: valgrind is not installed" >&2; exit 1; }
[ -x "$STEP_DRIVER" ] || { echo "step_instructions.sh: no $STEP_DRIVER: run ./build.sh fmus first" >&2; exit 1; }
mkdir -p "$OUT"

# config | scheme | description
CONFIGS=(
    "joint-off|1|n=1 joint, identifier off"
    "joint-off|2|n=1 joint, identifier off"
    "joint-lsm|1|n=1 joint, LSM, m=3"
    "joint-lsm|2|n=1 joint, LSM, m=3"
    "joint-mff|1|n=1 joint, MFF, m=3"
    "joint-mff|2|n=1 joint, MFF, m=3 (drift)"
    "ext-lsm|1|n=4 external, LSM, l=m=8"
    "ext-lsm|2|n=4 external, LSM, l=m=8"
    "ext-mff|1|n=4 external, MFF, l=m=8"
    "ext-mff|2|n=4 external, MFF, l=m=8"
    "joint-off|3|n=1 joint, identifier off"
    "joint-lsm|3|n=1 joint, LSM, m=3 + b"
    "joint-mff|3|n=1 joint, MFF, m=3 + b (drift)"
    "ext-lsm|3|n=4 external, LSM, l=m=8"
)

# Instructions collected inside fmi2DoStep for one run of the driver.
count() { # config scheme steps calls outfile
    local out
    out=$(valgrind --tool=callgrind --toggle-collect=fmi2DoStep --callgrind-out-file="$5" \
        "$STEP_DRIVER" "$1" "$2" "$3" "$4" 2>"$5.log") || {
        echo "step_instructions.sh: $1 scheme $2 failed:" >&2; cat "$5.log" >&2; exit 1; }
    local total
    total=$(awk '/^(summary|totals):/ {print $2; exit}' "$5")
    if [ -z "$total" ] || [ "$total" = 0 ]; then
        echo "step_instructions.sh: no instructions collected in fmi2DoStep ($5)" >&2; exit 1
    fi
    echo "$total $(echo "$out" | grep -o 'identifier_active=[01] converged=[01]')"
}

printf '%-30s %-8s %13s %10s %10s %12s %12s  %s\n' "configuration" "scheme" "Ir in doStep" \
    "Ir / step" "Ir / step" "Ir / step" "Ir / step" "state at the end"
printf '%-30s %-8s %13s %10s %10s %12s %12s\n' "" "" "" "H=${STEPS}h" "then" "H=h" "H=h then"
for entry in "${CONFIGS[@]}"; do
    IFS='|' read -r config scheme description <<< "$entry"
    [[ -z "${ONLY:-}" || "$config|$scheme" =~ $ONLY ]] || continue
    file="$OUT/callgrind.out.$config-s$scheme"
    read -r total state <<< "$(count "$config" "$scheme" "$STEPS" 1 "$file")"
    read -r total_2 _ <<< "$(count "$config" "$scheme" $((2 * STEPS)) 1 "$file-2")"
    read -r total_h _ <<< "$(count "$config" "$scheme" 1 "$STEPS" "$file-H=h")"
    read -r total_h2 _ <<< "$(count "$config" "$scheme" 1 $((2 * STEPS)) "$file-H=h-2")"
    per_step=$(awk -v t="$total" -v s="$STEPS" 'BEGIN {printf "%.1f", t / s}')
    then_step=$(awk -v t="$total" -v u="$total_2" -v s="$STEPS" 'BEGIN {printf "%.1f", (u - t) / s}')
    per_step_h=$(awk -v t="$total_h" -v s="$STEPS" 'BEGIN {printf "%.1f", t / s}')
    then_h=$(awk -v t="$total_h" -v u="$total_h2" -v s="$STEPS" 'BEGIN {printf "%.1f", (u - t) / s}')
    case "$scheme" in 1) label="1 paper" ;; 2) label="2 implicit" ;; *) label="3 default" ;; esac
    printf '%-30s %-8s %13s %10s %10s %12s %12s  %s\n' "$description" "$label" "$total" \
        "$per_step" "$then_step" "$per_step_h" "$then_h" "$state"
done
echo
echo "Ir = instructions executed inside fmi2DoStep (callgrind).  'H=${STEPS}h': one doStep of"
echo "$STEPS internal steps (+ one communication point), divided by $STEPS.  'then': the next $STEPS"
echo "steps (one doStep of $((2 * STEPS)) minus one of $STEPS, divided by $STEPS): the steady state,"
echo "after the start (scheme 3 runs its whole bank until its rankings settle).  'H=h': $STEPS doSteps"
echo "of one internal step each, as in the closed-loop harness, divided by $STEPS: internal step"
echo "+ communication point (outputs, identifier solve, checks) + the doStep entry checks."
echo "'H=h then': the next $STEPS doSteps of h (2 x $STEPS doSteps minus $STEPS): the steady state."
echo "Goals: n=1 joint LSM <= 200 instructions per internal step for schemes 1 and 2; <= 1500"
echo "for scheme 3, which runs a bank of linear observers beside scheme 2."
