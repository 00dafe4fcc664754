#!/usr/bin/env bash
# valgrind memcheck over a full closed-loop scenario of the FMUs (the shipped
# binaries that build.sh built), driven by tools/abuse/closed_loop.c (CMake's
# closed_loop target) through the plain FMI 2.0 C API: no memory errors and no
# definite or indirect leaks are allowed.
#
#   tools/abuse/memcheck.sh [SCENARIO [SECONDS]]     (default: 6.2, its full 40 s)
set -euo pipefail
cd "$(dirname "$0")/../.."
PY=.venv/bin/python
OUT=build/memcheck
SCENARIO=${1:-6.2}
die() { echo "memcheck.sh: $*" >&2; exit 1; }

if ! command -v valgrind >/dev/null; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get install -y -qq valgrind >/dev/null || { apt-get update -qq && apt-get install -y -qq valgrind >/dev/null; }
    fi
    command -v valgrind >/dev/null || die "valgrind is not installed (apt-get install -y valgrind)"
fi

./build.sh fmus >/dev/null
mkdir -p "$OUT"
CLOSED_LOOP=build/cmake/bin/closed_loop
"$PY" -m tools.abuse.plan "$SCENARIO" build build/fmus > "$OUT/plan.txt"
SECONDS_=${2:-$("$PY" -c "from harness.scenarios import SCENARIOS; print(SCENARIOS['$SCENARIO'].stop_time)")}

start=$(date +%s)
status=0
valgrind --tool=memcheck --error-exitcode=99 --leak-check=full \
    --show-leak-kinds=definite,indirect --errors-for-leak-kinds=definite,indirect \
    --track-origins=yes --log-file="$OUT/valgrind.log" \
    "$CLOSED_LOOP" "$OUT/plan.txt" "$SECONDS_" || status=$?
cat "$OUT/valgrind.log" | grep -E "ERROR SUMMARY|definitely lost|indirectly lost|possibly lost|still reachable|in use at exit" || true
echo "memcheck.sh: scenario $SCENARIO, $SECONDS_ s of model time, $(( $(date +%s) - start )) s under valgrind"
[ "$status" -eq 0 ] || die "valgrind reported errors or leaks (exit status $status): see $OUT/valgrind.log"
