#!/usr/bin/env bash
# Builds the libFuzzer targets (clang -fsanitize=fuzzer,address,undefined) for
# each FMU and runs each for a bounded time, starting from the seed corpus in
# tools/abuse/corpus/ (copied: the committed corpus is not changed).
#
#   tools/abuse/fuzz.sh                  every target, FUZZ_SECONDS each (default 30)
#   FUZZ_SECONDS=60 tools/abuse/fuzz.sh fuzz_calls SuperTwistingObserver
#   FUZZ_FORGED=0 ...                    leave out the forged-checksum states
#
# Targets: fuzz_deserialize (fmi2DeSerializeFMUstate of arbitrary bytes),
# fuzz_calls (random FMI 2 call sequences), fuzz_fmi3_calls (random FMI 3 call
# sequences, states serialized, damaged and forged) and fuzz_model_resource
# (ModelObserver's resources/model.txt, then inputs of any value, doSteps and states
# of the instance that read it); each is linked statically with
# its FMI API file, the model and the same core objects as the FMUs (CMake preset
# `fuzz`).
# A crash leaves its input in build/fuzz/artifacts/ and fails the script.
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$PWD
PY=$REPO/.venv/bin/python
OUT=$REPO/build/fuzz
SECONDS_EACH=${FUZZ_SECONDS:-30}
TARGETS=(${1:-fuzz_deserialize fuzz_calls fuzz_fmi3_calls fuzz_model_resource})
MODELS=(${2:-$("$PY" -m tools.fmu_models)})
die() { echo "fuzz.sh: $*" >&2; exit 1; }
log() { printf '\033[1m== %s\033[0m\n' "$*"; }

CLANG=${CLANG:-clang}
probe_fuzzer() {
    command -v "$CLANG" >/dev/null || return 1
    echo 'int LLVMFuzzerTestOneInput(const char *d, unsigned long n) { (void)d; return (int)n * 0; }' \
        > "$OUT/probe.c"
    "$CLANG" -fsanitize=fuzzer,address,undefined -o "$OUT/probe" "$OUT/probe.c" 2>/dev/null
}
mkdir -p "$OUT"
if ! probe_fuzzer; then
    log "installing clang with libFuzzer (Debian: clang, libclang-rt-dev)"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq >/dev/null
        apt-get install -y -qq clang >/dev/null
        # the runtime (libclang_rt.fuzzer) is in libclang-rt-<version>-dev since LLVM 14
        version=$(clang --version | sed -n 's/.*clang version \([0-9]*\).*/\1/p' | head -1)
        apt-get install -y -qq "libclang-rt-$version-dev" >/dev/null 2>&1 || true
    fi
    probe_fuzzer || die "clang with -fsanitize=fuzzer is not available (apt-get install -y clang libclang-rt-14-dev)"
fi

log "the Python environment and FMUs (build.sh fmus)"
./build.sh fmus >/dev/null
export PATH=$REPO/.venv/bin:$PATH  # the pinned cmake and ninja
FORGED=ON
[ "${FUZZ_FORGED:-1}" = 1 ] || FORGED=OFF
log "building the fuzz targets (cmake preset fuzz)"
cmake --preset fuzz -DCMAKE_C_COMPILER="$CLANG" -DSTO_FUZZ_FORGED=$FORGED >/dev/null
cmake --build --preset fuzz

mkdir -p "$OUT/artifacts"
summary=()
failed=0
for target in "${TARGETS[@]}"; do
    for id in "${MODELS[@]}"; do
        # the resource file's target is ModelObserver's alone
        [ "$target" != fuzz_model_resource ] || [ "$id" = ModelObserver ] || continue
        binary=$REPO/build/cmake-fuzz/bin/$target-$id
        [ -x "$binary" ] || die "$binary was not built"
        corpus=$OUT/corpus/$target/$id
        rm -rf "$corpus" && mkdir -p "$corpus"
        seeds=tools/abuse/corpus/$target
        [ -d "$seeds/$id" ] && seeds=$seeds/$id
        if [ "$target" = fuzz_deserialize ] && [ ! -d "tools/abuse/corpus/$target/$id" ]; then
            # large states are not committed: seeds from this build
            "$PY" -m tools.abuse.make_corpus --into "$OUT/seeds" "$id" >/dev/null
            seeds=$OUT/seeds/$target/$id
        fi
        [ -d "$seeds" ] || die "no seed corpus $seeds (commit one: a few inputs as files)"
        log "$target on $id for $SECONDS_EACH s (seeds: $(find "$seeds" -maxdepth 1 -type f | wc -l))"
        status=0
        ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1 \
            "$binary" -max_total_time="$SECONDS_EACH" -timeout=20 -rss_limit_mb=2048 \
            -print_final_stats=1 -artifact_prefix="$OUT/artifacts/$target-$id-" \
            "$corpus" "$seeds" > "$OUT/$target-$id.log" 2>&1 || status=$?
        runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$OUT/$target-$id.log" || true)
        speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$OUT/$target-$id.log" || true)
        cov=$( (grep -E '^#[0-9]+' "$OUT/$target-$id.log" || true) | tail -1 |
              sed -n 's/.*cov: \([0-9]*\) ft: \([0-9]*\) corp: \([0-9]*\).*/cov \1, ft \2, corpus \3/p')
        if [ "$status" -ne 0 ]; then
            failed=1
            grep -E 'ERROR|FUZZ INVARIANT|runtime error|SUMMARY|Test unit written|#[0-9] 0x' \
                "$OUT/$target-$id.log" | head -30 >&2 || true
            summary+=("$target $id: FAILED (exit $status) after ${runs:-?} runs; log $OUT/$target-$id.log")
        else
            summary+=("$target $id: ${runs:-?} runs, ${speed:-?} exec/s, ${cov:-}")
        fi
    done
done
log "summary"
printf '  %s\n' "${summary[@]}"
[ "$failed" = 0 ] || die "a fuzz target crashed or broke an invariant (inputs in $OUT/artifacts/)"
