#!/usr/bin/env bash
# Builds, packages and validates the project's FMUs, then runs what was asked.
#
#   ./build.sh            build the FMUs, then run the closed-loop demonstration
#   ./build.sh test       build the FMUs, install the importers (FMI4j, fmi-sim), run the tests
#   ./build.sh fmus       build the FMUs only
#   ./build.sh dist       build the FMUs, then the distribution FMUs with binaries for
#                         Linux (x86_64, aarch64), Windows (x86_64) and macOS (x86_64,
#                         aarch64), installing the cross toolchains (cached; tools/dist/)
#
# On a fresh machine it first creates .venv from the pinned requirements.txt.
# Outputs go to build/: FMI 2.0 FMUs in build/fmus/, FMI 3.0 FMUs in build/fmi3/,
# distribution FMUs in build/dist/fmi2/ and build/dist/fmi3/.
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
    "SuperTwistingObserver|models/observer.c|core/super_twisting.c core/implicit_twisting.c core/noise_adaptive.c core/identifier.c core/information_identifier.c core/block_scores.c core/gains.c|fmu/modelDescription.xml"
    "Pendulum|models/pendulum.c||fmu/bench/Pendulum/modelDescription.xml"
    "TwistingController|models/twisting_controller.c||fmu/bench/TwistingController/modelDescription.xml"
    "RobotObserver|models/robot_observer.c|core/robot_observer.c core/rigid_body.c core/regressor_identifier.c core/statistics_job.c core/gains.c|fmu/robot/modelDescription.xml"
)

# Sources of one FMU, relative to fmu/src: the API file, the instance core, the model
# and its core files (the model files are everything after the first two).
fmu_sources() { # fmi_version model core
    echo "fmi$1/fmi$1_functions.c instance/instance.c $2 $3"
}

fmi_include() {
    "$PY" -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))'
}

# Where one FMU is laid out and packed: FMI 2 as before (build/<id>, whose sources
# tools/abuse/ recompiles; build/fmus/<id>.fmu), FMI 3 in build/fmi3/.
fmu_dir() { if [ "$1" = 2 ]; then echo "$BUILD/$2"; else echo "$BUILD/fmi3/$2"; fi; }
fmu_file() { if [ "$1" = 2 ]; then echo "$BUILD/fmus/$2.fmu"; else echo "$BUILD/fmi3/$2.fmu"; fi; }
# The committed FMI 3 description sits in fmi3/ next to the FMI 2 one.
committed_xml() { # fmi_version fmi2_xml
    if [ "$1" = 2 ]; then echo "$2"; else echo "$(dirname "$2")/fmi3/modelDescription.xml"; fi
}
# The binaries folder of this machine's build (FMI 2 platform name, FMI 3 platform tuple).
host_platform() { if [ "$1" = 2 ]; then echo linux64; else echo x86_64-linux; fi; }

# The XML is generated from the C variable table and must match the committed one;
# sources/buildDescription.xml lists the same sources.
describe_fmu() { # fmi_version out xml sources...
    local fmi=$1 out=$2 xml=$3; shift 3
    local src=fmu/src f model_files=()
    for f in "${@:3}"; do model_files+=("$src/$f"); done
    "$CC" "${CFLAGS[@]}" -o "$out/describe_model" fmu/tools/describe_model.c "${model_files[@]}" -lm
    "$out/describe_model" "fmi$fmi" "$@" > "$out/modelDescription.xml"
    "$out/describe_model" build "$@" > "$out/sources/buildDescription.xml"
    if ! cmp -s "$out/modelDescription.xml" "$xml"; then
        diff -u "$xml" "$out/modelDescription.xml" | head -40 || true
        echo "build.sh: $xml is out of date with the variable table in $src/${3}." >&2
        echo "          Regenerate it: mkdir -p $(dirname "$xml") && cp $out/modelDescription.xml $xml" >&2
        exit 1
    fi
}

# Only the FMI functions of the given version may be exported.
check_exports() { # binary fmi_version
    local extra
    extra=$(nm -D --defined-only "$1" | awk '{print $3}' | grep -v "^fmi$2" || true)
    if [ -n "$extra" ]; then echo "build.sh: $1 exports non-FMI symbols: $extra" >&2; exit 1; fi
}

# Sources keep their layout under sources/ so that `fmpy compile` can rebuild them.
copy_sources() { # out sources...
    local out=$1 src=fmu/src f; shift
    for f in "$@" instance/instance.h instance/model_interface.h $(cd "$src" && echo core/*.h); do
        mkdir -p "$out/sources/$(dirname "$f")"
        cp "$src/$f" "$out/sources/$f"
    done
}

build_fmu() { # fmi_version id model core xml
    local fmi=$1 id=$2 model=$3 core=$4
    local xml out platform f sources paths=()
    xml=$(committed_xml "$fmi" "$5")
    out=$(fmu_dir "$fmi" "$id")
    platform=$(host_platform "$fmi")
    read -r -a sources <<< "$(fmu_sources "$fmi" "$model" "$core")"
    rm -rf "$out" && mkdir -p "$out/binaries/$platform" "$out/sources"
    describe_fmu "$fmi" "$out" "$xml" "${sources[@]}"
    for f in "${sources[@]}"; do paths+=("fmu/src/$f"); done
    "$CC" "${CFLAGS[@]}" -shared -I "$(fmi_include)" -o "$out/binaries/$platform/$id.so" \
        "${paths[@]}" -lm
    check_exports "$out/binaries/$platform/$id.so" "$fmi"
    copy_sources "$out" "${sources[@]}"
    "$PY" -m harness.package "$out" "$(fmu_file "$fmi" "$id")"
}

build_all() {
    local fmi entry id model core xml
    mkdir -p "$BUILD/fmus" "$BUILD/fmi3"
    for fmi in 2 3; do
        for entry in "${MODELS[@]}"; do
            IFS='|' read -r id model core xml <<< "$entry"
            log "building $id.fmu (FMI $fmi)"
            build_fmu "$fmi" "$id" "$model" "$core" "$xml"
        done
    done
    log "reference results of the default experiments (FMI-LS-REF)"
    "$PY" tools/importers/make_reference.py "$BUILD"/fmus/*.fmu "$BUILD"/fmi3/*.fmu
    log "validating with fmpy"
    "$PY" -m harness.package --validate "$BUILD"/fmus/*.fmu "$BUILD"/fmi3/*.fmu
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
    dist) bash tools/dist/build_dist.sh ;;
    *) echo "usage: $0 [demo|test|fmus|dist]" >&2; exit 2 ;;
esac
