#!/usr/bin/env bash
# Builds the three FMUs' shared libraries (FMI 2 and FMI 3) with AddressSanitizer and
# UndefinedBehaviorSanitizer (any report aborts) and runs the FMI, abuse and
# master-loop tests against them.
#
#   tools/abuse/sanitize.sh [extra pytest arguments]
#
# Same sources and FMI headers as build.sh: it runs `./build.sh fmus` first and
# recompiles exactly the C files that build.sh shipped in build/<id>/sources/.
# The sanitized FMUs go to build/sanitize/fmus/; the tests find them through
# $STO_FMU_DIR (tests/abuse) and the plugin tools/abuse/sanitized_fmus.py
# (tests/conftest.py's fixtures).  libasan is preloaded into the Python process.
# tests/fmu/test_binaries.py is left out: it checks the shipped binaries' linkage,
# which a sanitized build changes on purpose (libasan, libubsan).
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$PWD
PY=$REPO/.venv/bin/python
OUT=$REPO/build/sanitize
MODELS=(SuperTwistingObserver Pendulum TwistingController RobotObserver)
CC=${CC:-gcc}
SANITIZE=(-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all
          -fno-omit-frame-pointer)
CFLAGS=(-std=c11 -Wall -Wextra -Wpedantic -Werror -O1 -g -fPIC -fvisibility=hidden)

log() { printf '\033[1m== %s\033[0m\n' "$*"; }
die() { echo "sanitize.sh: $*" >&2; exit 1; }

command -v "$CC" >/dev/null || die "no C compiler $CC"
LIBASAN=$("$CC" -print-file-name=libasan.so)
[ -f "$LIBASAN" ] || die "$CC has no libasan.so (Debian: apt-get install -y libasan8)"
"$CC" -print-file-name=libubsan.so | xargs test -f || die "$CC has no libubsan.so (apt-get install -y libubsan1)"

log "building the FMUs (build.sh fmus)"
./build.sh fmus >/dev/null

FMI_INCLUDE=$("$PY" -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')
rm -rf "$OUT" && mkdir -p "$OUT/fmus" "$OUT/fmi3"
# FMI 2 layouts in build/<id> (binaries/linux64), FMI 3 in build/fmi3/<id> (binaries/x86_64-linux)
for fmi in 2 3; do
  for id in "${MODELS[@]}"; do
    if [ "$fmi" = 2 ]; then src=build/$id dst=$OUT/$id fmu=$OUT/fmus/$id.fmu platform=linux64
    else src=build/fmi3/$id dst=$OUT/fmi3/$id fmu=$OUT/fmi3/$id.fmu platform=x86_64-linux; fi
    [ -f "$src/modelDescription.xml" ] && [ -d "$src/sources" ] || die "$src is not an FMU layout"
    log "sanitized $id (FMI $fmi)"
    cp -r "$src" "$dst"
    rm -f "$dst/describe_model"
    mapfile -t sources < <(cd "$dst/sources" && find . -name '*.c' | sort)
    (cd "$dst/sources" && "$CC" "${CFLAGS[@]}" "${SANITIZE[@]}" -shared -I "$FMI_INCLUDE" \
        -o "$dst/binaries/$platform/$id.so" "${sources[@]}" -lm)
    symbols=$(nm -D "$dst/binaries/$platform/$id.so")
    grep -q " T fmi${fmi}DoStep\$" <<< "$symbols" || die "$id.so does not export fmi${fmi}DoStep"
    grep -q ' U __asan_report_load8$' <<< "$symbols" || die "$id.so is not instrumented"
    "$PY" -m harness.package "$dst" "$fmu"
  done
done

log "tests against the sanitized FMUs"
export STO_FMU_DIR=$OUT/fmus
export STO_FMI3_DIR=$OUT/fmi3
export STO_EXPECT_SANITIZED=1
export PYTHONPATH=$REPO/tools/abuse${PYTHONPATH:+:$PYTHONPATH}
# Python itself leaks by design at exit: leaks are memcheck.sh's business.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=0:halt_on_error=1:exitcode=86:print_summary=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=87
start=$(date +%s)
status=0
# tests/abuse/test_cli_input.py and test_sweep_input.py drive the harness command line
# (matplotlib, dask), not the FMUs' C code beyond what the other tests call, and
# matplotlib's C++ extension aborts under a preloaded libasan (__cxa_throw CHECK).
LD_PRELOAD=$LIBASAN "$PY" -m pytest -q -p sanitized_fmus -p no:cacheprovider \
    --ignore=tests/fmu/test_binaries.py --ignore=tests/abuse/test_cli_input.py \
    --ignore=tests/abuse/test_sweep_input.py \
    tests/abuse tests/fmu tests/harness/test_master.py "$@" || status=$?
log "sanitized tests: exit status $status ($(( $(date +%s) - start )) s)"
[ "$status" -eq 0 ] || die "tests failed or a sanitizer reported an error (see above)"
