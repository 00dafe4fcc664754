#!/usr/bin/env bash
# The one entry point of the build: a thin driver over CMake (CMakeLists.txt, presets
# in CMakePresets.json) and the pinned Python environment.
#
#   ./build.sh            build the FMUs, then run the closed-loop demonstration
#   ./build.sh test       build, install the importers (FMI4j, fmi-sim), run the C tests, the
#                         linter and type checker (ruff, mypy) and the Python tests
#   ./build.sh fmus       build the FMUs only
#   ./build.sh wheel      build the FMUs, then the Python wheel (build/wheel/)
#   ./build.sh docs       the Python API documentation (build/api/)
#   ./build.sh dist       build the FMUs, then the distribution FMUs with binaries for
#                         Linux (x86_64, aarch64), Windows (x86_64) and macOS (x86_64,
#                         aarch64), installing the cross toolchains (cached; tools/dist/)
#
# On a fresh machine it first creates .venv from the pinned requirements.txt.  CMake
# rebuilds only what changed.  Outputs go to build/: FMI 2.0 FMUs in build/fmus/, FMI 3.0
# FMUs in build/fmi3/, the CMake tree in build/cmake/, the package's native library in
# harness/lib/, distribution FMUs in build/dist/fmi2/ and build/dist/fmi3/.
set -euo pipefail
cd "$(dirname "$0")"

COMMAND=${1:-demo}
case "$COMMAND" in
    demo|test|fmus|wheel|docs|dist) ;;
    *) echo "usage: $0 [demo|test|fmus|wheel|docs|dist]" >&2; exit 2 ;;
esac

VENV=.venv
PY=$VENV/bin/python
BUILD=build

log() { printf '\033[1m== %s\033[0m\n' "$*"; }

# ---- Python environment (pinned) -------------------------------------------
setup_venv() {
    local stamp=$VENV/.requirements.sha
    local want
    want=$(cat requirements.txt pyproject.toml | sha256sum | cut -d' ' -f1)
    if ! [ -x "$PY" ] || ! [ -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
        log "creating $VENV from requirements.txt"
        python3 -m venv "$VENV"
        "$PY" -m pip install --quiet --disable-pip-version-check -r requirements.txt
        echo "$want" > "$stamp"
        rm -f "$VENV/.package.sha"
    fi
    install_package
}

# The harness itself, editable.  The editable install maps the package's modules by
# their paths when it is made, so it is made again when a module is added, moved or
# removed (a stale map fails the import of a moved module).
install_package() {
    local stamp=$VENV/.package.sha
    local want
    want=$( (cat pyproject.toml; find harness -name '*.py' | sort) | sha256sum | cut -d' ' -f1)
    if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then return; fi
    log "installing the harness into $VENV (editable)"
    "$PY" -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation \
        -e .
    echo "$want" > "$stamp"
}

# ---- the C build (CMake: FMUs, checks, native library, C tests, drivers) ----
build_c() {
    export PATH=$PWD/$VENV/bin:$PATH  # the pinned cmake and ninja
    if [ ! -f "$BUILD/cmake/CMakeCache.txt" ]; then
        cmake --preset default -DSTO_PYTHON="$PWD/$PY" >/dev/null
    fi
    log "building (cmake --build --preset default)"
    cmake --build --preset default
}

build_wheel() {
    log "building the wheel into $BUILD/wheel"
    rm -rf "$BUILD/wheel"
    "$PY" -m pip wheel --quiet --disable-pip-version-check --no-deps --no-build-isolation \
        -Ccmake.define.STO_WHEEL_FMU_DIR="$PWD/$BUILD/fmus" --wheel-dir "$BUILD/wheel" .
}

setup_venv
[ "$COMMAND" = docs ] || build_c
case "$COMMAND" in
    fmus) ;;
    wheel) build_wheel ;;
    docs) rm -rf "$BUILD/api"; "$PY" -m pdoc --output-directory "$BUILD/api" harness ;;
    test)
        build_wheel
        # The tests run every FMU in two independent importers too (tests/importers).
        log "installing the independent FMI importers (cached)"
        bash tools/importers/install.sh
        log "C tests (ctest)"
        ctest --preset default
        log "linter and type checker (ruff, mypy)"
        "$PY" -m ruff check .
        "$PY" -m mypy
        log "Python tests"
        "$PY" -m pytest -q tests ;;
    demo) log "closed-loop demonstration"; "$PY" -m harness demo --out "$BUILD/demo" ;;
    dist) bash tools/dist/build_dist.sh ;;
esac
