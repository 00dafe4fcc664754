#!/usr/bin/env bash
# Distribution FMUs (`./build.sh dist`): the FMUs that `./build.sh fmus` made (with
# their sources, reference results and x86_64 Linux binary), plus binaries
# cross-compiled by the same CMake build (one preset and toolchain file a platform,
# cmake/toolchains/) for
#
#   FMI 3 tuple     FMI 2 folder   compiler
#   x86_64-linux    linux64        gcc (the native build)
#   aarch64-linux   -              aarch64-linux-gnu-gcc (Debian)
#   x86_64-windows  win64          x86_64-w64-mingw32-gcc (Debian mingw-w64)
#   x86_64-darwin   darwin64       zig cc -target x86_64-macos (PyPI ziglang)
#   aarch64-darwin  -              zig cc -target aarch64-macos
#
# FMI 2.0 names no folders for aarch64, so the FMI 2 FMUs carry three platforms.
# Into build/dist/fmi2/ and build/dist/fmi3/.  Every binary's exported symbols are
# checked: only the FMI functions of its version (Mach-O dylibs also export the two
# symbols every dylib has, __mh_dylib_header and ___dso_handle); the Windows DLLs may
# import only KERNEL32.dll and msvcrt.dll (no MinGW runtime DLL to ship).
set -euo pipefail
cd "$(dirname "$0")/../.."

PY=$PWD/.venv/bin/python
BUILD=build
OUT=$BUILD/dist
MODELS=($("$PY" -m tools.fmu_models))

log() { printf '\033[1m== %s\033[0m\n' "$*"; }
die() { echo "build_dist.sh: $*" >&2; exit 1; }

eval "$(bash tools/dist/install_toolchains.sh)"
export ZIG ZIG_GLOBAL_CACHE_DIR ZIG_LOCAL_CACHE_DIR
export PATH=$PWD/.venv/bin:$PATH  # the pinned cmake and ninja

# FMI 3 tuple (= the CMake preset) | FMI 2 folder (- for none) | extension
PLATFORMS=(
    "aarch64-linux|-|so"
    "x86_64-windows|win64|dll"
    "x86_64-darwin|darwin64|dylib"
    "aarch64-darwin|-|dylib"
)
for entry in "${PLATFORMS[@]}"; do
    tuple=${entry%%|*}
    log "cross build $tuple (cmake preset $tuple)"
    cmake --preset "$tuple" -DSTO_PYTHON="$PY" >/dev/null
    cmake --build --preset "$tuple"
done

# The symbols a binary exports, one a line (ELF, PE or Mach-O by extension).
exported_symbols() { # binary extension
    case $2 in
        so) llvm-nm -D --defined-only "$1" | awk '{print $3}' ;;
        dll) x86_64-w64-mingw32-objdump -p "$1" |
                 sed -n '/\[Ordinal\/Name Pointer\] Table/,/^$/p' | sed -n 's/^\s*\[ *[0-9]*\] //p' ;;
        dylib) llvm-objdump --macho --exports-trie "$1" | awk 'NR > 3 {print $2}' |
                   grep -vx '__mh_dylib_header\|___dso_handle' | sed 's/^_//' ;;
    esac
}

check_binary() { # binary extension fmi_version
    local symbols extra
    symbols=$(exported_symbols "$1" "$2")
    grep -qx "fmi$3DoStep" <<< "$symbols" || die "$1 does not export fmi$3DoStep"
    extra=$(grep -v "^fmi$3" <<< "$symbols" || true)
    [ -z "$extra" ] || die "$1 exports non-FMI symbols: $extra"
    if [ "$2" = dll ]; then
        extra=$(x86_64-w64-mingw32-objdump -p "$1" | sed -n 's/^\s*DLL Name: //p' |
                grep -vix 'KERNEL32.dll\|msvcrt.dll' || true)
        [ -z "$extra" ] || die "$1 needs DLLs a plain Windows lacks: $extra"
    fi
    echo "  $1: $(wc -l <<< "$symbols") FMI functions exported, nothing else"
}

build_dist_fmu() { # fmi_version id
    local fmi=$1 id=$2 layout native fmu entry tuple folder ext platform
    if [ "$fmi" = 2 ]; then layout=$BUILD/$id native=$BUILD/fmus/$id.fmu
    else layout=$BUILD/fmi3/$id native=$BUILD/fmi3/$id.fmu; fi
    [ -f "$native" ] && [ -d "$layout/sources" ] || die "$native missing: run ./build.sh fmus"
    fmu=$OUT/fmi$fmi/$id.fmu
    local stage=$OUT/fmi$fmi/$id
    rm -rf "$stage" && mkdir -p "$stage"
    for entry in "${PLATFORMS[@]}"; do
        IFS='|' read -r tuple folder ext <<< "$entry"
        platform=$([ "$fmi" = 2 ] && echo "$folder" || echo "$tuple")
        [ "$platform" != - ] || continue
        local built=$BUILD/dist/$tuple/$id
        [ "$fmi" = 2 ] || built=$BUILD/dist/$tuple/fmi3/$id
        mkdir -p "$stage/binaries/$platform"
        cp "$built/binaries/$platform/$id.$ext" "$stage/binaries/$platform/"
    done
    cp "$native" "$fmu"
    "$PY" - "$fmu" "$stage" <<'EOF'
import sys, zipfile
from pathlib import Path
fmu, stage = sys.argv[1], Path(sys.argv[2])
with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as archive:
    for path in sorted((stage / "binaries").rglob("*")):
        if path.is_file():
            archive.write(path, path.relative_to(stage).as_posix())
EOF
    mkdir -p "$stage/check" && (cd "$stage/check" && "$PY" -m zipfile -e "$OLDPWD/$fmu" .)
    for binary in "$stage"/check/binaries/*/*; do check_binary "$binary" "${binary##*.}" "$fmi"; done
    rm -rf "$stage/check"
}

for fmi in 2 3; do
    mkdir -p "$OUT/fmi$fmi"
    for id in "${MODELS[@]}"; do
        log "distribution $id.fmu (FMI $fmi)"
        build_dist_fmu "$fmi" "$id"
    done
done
log "validating with fmpy"
"$PY" -m harness.package --validate "$OUT"/fmi2/*.fmu "$OUT"/fmi3/*.fmu
