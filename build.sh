#!/usr/bin/env bash
# Builds, packages and validates the project's FMUs, then runs what was asked.
#
#   ./build.sh            build the FMUs, then run the closed-loop demonstration
#   ./build.sh test       build the FMUs, install the importers (FMI4j, fmi-sim), run the tests
#   ./build.sh fmus       build the FMUs only
#
# On a fresh machine it first creates .venv from the pinned requirements.txt.
# Outputs go to build/ (FMUs in build/fmus/).
set -euo pipefail
cd "$(dirname "$0")"

VENV=.venv
PY=$VENV/bin/python
BUILD=build
CC=${CC:-gcc}
CFLAGS=(-std=c11 -Wall -Wextra -Wpedantic -Werror -O2 -fPIC -fvisibility=hidden)

log() { printf '\033[1m== %s\033[0m\n' "$*"; }

# ---- Python environment (pinned) -------------------------------------------
setup_venv() {
    local stamp=$VENV/.requirements.sha
    local want
    want=$(cat requirements.txt pyproject.toml | sha256sum | cut -d' ' -f1)
    if [ -x "$PY" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then return; fi
    log "creating $VENV from requirements.txt"
    python3 -m venv "$VENV"
    "$PY" -m pip install --quiet --disable-pip-version-check -r requirements.txt
    "$PY" -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
    echo "$want" > "$stamp"
}

# ---- FMUs --------------------------------------------------------------------
# model identifier | model file | core files | committed modelDescription.xml
MODELS=(
    "SuperTwistingObserver|models/observer.c|core/super_twisting.c core/implicit_twisting.c core/noise_adaptive.c core/identifier.c core/information_identifier.c core/gains.c|fmu/modelDescription.xml"
    "Pendulum|models/pendulum.c||fmu/bench/Pendulum/modelDescription.xml"
    "TwistingController|models/twisting_controller.c||fmu/bench/TwistingController/modelDescription.xml"
)

build_fmu() {
    local id=$1 model=$2 core=$3 xml=$4
    local fmi_include src=fmu/src out=$BUILD/$id
    fmi_include=$("$PY" -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')
    local sources=(fmi2/fmi2_layer.c "$model")
    local f
    for f in $core; do sources+=("$f"); done
    local model_files=()   # the model and its core files, without the FMI layer
    for f in "${sources[@]:1}"; do model_files+=("$src/$f"); done
    rm -rf "$out" && mkdir -p "$out/binaries/linux64" "$out/sources"

    # The XML is generated from the C variable table and must match the committed one.
    "$CC" "${CFLAGS[@]}" -o "$out/describe_model" fmu/tools/describe_model.c "${model_files[@]}" -lm
    "$out/describe_model" "${sources[@]}" > "$out/modelDescription.xml"
    if ! cmp -s "$out/modelDescription.xml" "$xml"; then
        diff -u "$xml" "$out/modelDescription.xml" | head -40 || true
        echo "build.sh: $xml is out of date with the variable table in $src/$model." >&2
        echo "          Regenerate it: cp $out/modelDescription.xml $xml" >&2
        exit 1
    fi

    "$CC" "${CFLAGS[@]}" -shared -I "$fmi_include" -o "$out/binaries/linux64/$id.so" \
        "$src/fmi2/fmi2_layer.c" "${model_files[@]}" -lm
    # Only the fmi2 functions may be exported.
    local extra
    extra=$(nm -D --defined-only "$out/binaries/linux64/$id.so" | awk '{print $3}' | grep -v '^fmi2' || true)
    if [ -n "$extra" ]; then echo "build.sh: $id exports non-FMI symbols: $extra" >&2; exit 1; fi

    # Sources keep their layout under sources/ so that `fmpy compile` can rebuild them.
    for f in "${sources[@]}" fmi2/model_interface.h $(cd "$src" && echo core/*.h); do
        mkdir -p "$out/sources/$(dirname "$f")"
        cp "$src/$f" "$out/sources/$f"
    done
    "$PY" -m harness.package "$out" "$BUILD/fmus/$id.fmu"
}

build_all() {
    mkdir -p "$BUILD/fmus"
    for entry in "${MODELS[@]}"; do
        IFS='|' read -r id model core xml <<< "$entry"
        log "building $id.fmu"
        build_fmu "$id" "$model" "$core" "$xml"
    done
    log "reference results of the default experiments (FMI-LS-REF)"
    "$PY" tools/importers/make_reference.py "$BUILD"/fmus/*.fmu
    log "validating with fmpy"
    "$PY" -m harness.package --validate "$BUILD"/fmus/*.fmu
    log "writing the closed loop as SSP"
    "$PY" -m harness.ssp "$BUILD/fmus" "$BUILD/ClosedLoop.ssp"
}

# ---- the Python package: FMUs as package data, a wheel, the API documentation ----
package_python() {
    log "packaging the harness: FMUs into harness/data, C core into harness/robot/core, wheel into $BUILD/wheel, API docs"
    rm -rf harness/data && mkdir -p harness/data
    cp "$BUILD"/fmus/*.fmu harness/data/
    # the C core that harness.robot.native compiles, for an installed package
    rm -rf harness/robot/core && mkdir -p harness/robot/core
    cp fmu/src/core/*.c fmu/src/core/*.h harness/robot/core/
    rm -rf "$BUILD/wheel" "$BUILD/api"
    "$PY" -m pip wheel --quiet --disable-pip-version-check --no-deps --no-build-isolation \
        --wheel-dir "$BUILD/wheel" .
    "$PY" -m pdoc --output-directory "$BUILD/api" harness
}

setup_venv
build_all
package_python
case "${1:-demo}" in
    fmus) ;;
    test)
        # The tests run every FMU in two independent importers too (tests/importers).
        log "installing the independent FMI importers (cached)"
        bash tools/importers/install.sh
        log "running tests"
        "$PY" -m pytest -q tests ;;
    demo) log "closed-loop demonstration"; "$PY" -m harness demo --out "$BUILD/demo" ;;
    *) echo "usage: $0 [demo|test|fmus]" >&2; exit 2 ;;
esac
