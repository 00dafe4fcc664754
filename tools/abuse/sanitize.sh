#!/usr/bin/env bash
# Builds the FMUs (FMI 2 and FMI 3) and the C core tests with AddressSanitizer and
# UndefinedBehaviorSanitizer (any report aborts; CMake preset `sanitize`, the same
# sources and build as every other consumer), runs the C tests (ctest), then the FMI,
# abuse and master-loop tests against the sanitized FMUs.
#
#   tools/abuse/sanitize.sh [extra pytest arguments]
#
# The sanitized FMUs go to build/sanitize/fmus/ and build/sanitize/fmi3/; the tests find
# them through $STO_FMU_DIR (abuse_fmi.py, tests/cli_runner.py) and the plugin tools/abuse/sanitized_fmus.py
# (tests/conftest.py's fixtures).  libasan is preloaded into the Python process.
# tests/fmu/test_binaries.py is left out: it checks the shipped binaries' linkage,
# which a sanitized build changes on purpose (libasan, libubsan).
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$PWD
PY=$REPO/.venv/bin/python
OUT=$REPO/build/sanitize
MODELS=($("$PY" -m tools.fmu_models))
CC=${CC:-gcc}

log() { printf '\033[1m== %s\033[0m\n' "$*"; }
die() { echo "sanitize.sh: $*" >&2; exit 1; }

command -v "$CC" >/dev/null || die "no C compiler $CC"
LIBASAN=$("$CC" -print-file-name=libasan.so)
[ -f "$LIBASAN" ] || die "$CC has no libasan.so (Debian: apt-get install -y libasan8)"
"$CC" -print-file-name=libubsan.so | xargs test -f || die "$CC has no libubsan.so (apt-get install -y libubsan1)"

log "the Python environment (build.sh fmus)"
./build.sh fmus >/dev/null
export PATH=$REPO/.venv/bin:$PATH  # the pinned cmake and ninja
log "sanitized build (cmake preset sanitize)"
cmake --preset sanitize -DSTO_PYTHON="$PY" >/dev/null
ASAN_OPTIONS=detect_leaks=0 cmake --build --preset sanitize
for fmi in 2 3; do
  for id in "${MODELS[@]}"; do
    if [ "$fmi" = 2 ]; then binary=$OUT/$id/binaries/linux64/$id.so
    else binary=$OUT/fmi3/$id/binaries/x86_64-linux/$id.so; fi
    symbols=$(nm -D "$binary")
    grep -q " T fmi${fmi}DoStep\$" <<< "$symbols" || die "$binary does not export fmi${fmi}DoStep"
    grep -q ' U __asan_report_load8$' <<< "$symbols" || die "$binary is not instrumented"
  done
done
log "C core tests under the sanitizers (ctest)"
ASAN_OPTIONS=detect_leaks=1 ctest --preset sanitize

log "tests against the sanitized FMUs"
export STO_FMU_DIR=$OUT/fmus
export STO_FMI3_DIR=$OUT/fmi3
export STO_EXPECT_SANITIZED=1
# Python itself leaks by design at exit: leaks are memcheck.sh's business.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=0:halt_on_error=1:exitcode=86:print_summary=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=87
start=$(date +%s)
status=0
# The tests marked cli drive the harness command line (matplotlib, dask), not the
# FMUs' C code beyond what the other tests call, and matplotlib's C++ extension
# aborts under a preloaded libasan (__cxa_throw CHECK).
LD_PRELOAD=$LIBASAN "$PY" -m pytest -q -p tools.abuse.sanitized_fmus -p no:cacheprovider -m "not cli" \
    --ignore=tests/fmu/test_binaries.py \
    tests/fmu tests/harness/test_master.py tests/harness/model/test_model_fmu_nonfinite.py \
    "$@" || status=$?
log "sanitized tests: exit status $status ($(( $(date +%s) - start )) s)"
[ "$status" -eq 0 ] || die "tests failed or a sanitizer reported an error (see above)"
