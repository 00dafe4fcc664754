#!/usr/bin/env bash
# Runs the cross-compiled binaries of the distribution FMUs (build/dist/, made by
# `./build.sh dist`) where this machine can: each FMU's default experiment through
# tools/dist/run_reference.c, a small C importer built for the same platform,
# compared with the reference result the FMU ships (FMI-LS-REF):
#
#   x86_64-linux    natively
#   aarch64-linux   under qemu-user (qemu-aarch64, Debian's arm64 libc)
#   x86_64-windows  under wine (wine64)
#
# The macOS binaries (x86_64-darwin, aarch64-darwin; FMI 2 darwin64) are built and
# their exports checked by build_dist.sh, but cannot run here.  Tolerance: 1e-9 of
# max(1, max |reference column|), as tools/importers/check.py.
set -euo pipefail
cd "$(dirname "$0")/../.."

PY=$PWD/.venv/bin/python
DIST=build/dist
OUT=build/dist/check
MODELS=($("$PY" -m tools.fmu_models))

log() { printf '\033[1m== %s\033[0m\n' "$*"; }
die() { echo "check_platforms.sh: $*" >&2; exit 1; }

eval "$(bash tools/dist/install_toolchains.sh)"
export WINEPREFIX WINEDEBUG=-all
rm -rf "$OUT" && mkdir -p "$OUT"

# The importer of each platform, built by the same CMake build as the FMUs (build.sh
# and build_dist.sh's presets: the run_reference target).
NATIVE_IMPORTER=build/cmake/bin/run_reference
AARCH64_IMPORTER=build/cmake-aarch64-linux/bin/run_reference
WINDOWS_IMPORTER=build/cmake-x86_64-windows/bin/run_reference.exe
for importer in "$NATIVE_IMPORTER" "$AARCH64_IMPORTER" "$WINDOWS_IMPORTER"; do
    [ -x "$importer" ] || die "$importer missing: run ./build.sh dist"
done

# Wine wants Windows paths: the Z: drive is the host's root.
windows_path() { echo "Z:$(realpath "$1" | tr / '\\')"; }

# FMI version | runner | platform folder | binary extension | importer
RUNS=(
    "2|native|linux64|so|$NATIVE_IMPORTER"
    "2|wine|win64|dll|$WINDOWS_IMPORTER"
    "3|native|x86_64-linux|so|$NATIVE_IMPORTER"
    "3|qemu|aarch64-linux|so|$AARCH64_IMPORTER"
    "3|wine|x86_64-windows|dll|$WINDOWS_IMPORTER"
)
failed=0
summary=()
for id in "${MODELS[@]}"; do
    for fmi in 2 3; do
        fmu=$DIST/fmi$fmi/$id.fmu
        [ -f "$fmu" ] || die "$fmu missing: run ./build.sh dist"
        work=$OUT/fmi$fmi-$id
        mkdir -p "$work" && (cd "$work" && "$PY" -m zipfile -e "$OLDPWD/$fmu" .)
        "$PY" -m tools.dist.plan "$fmu" "$work/plan.txt" >/dev/null
        for run in "${RUNS[@]}"; do
            IFS='|' read -r version runner platform ext importer <<< "$run"
            [ "$version" = "$fmi" ] || continue
            binary=$work/binaries/$platform/$id.$ext
            [ -f "$binary" ] || die "$fmu has no binaries/$platform/$id.$ext"
            status=0
            case $runner in
                native) line=$("$importer" "$work/plan.txt" "$binary" 2>&1) || status=$? ;;
                qemu) line=$(qemu-aarch64 -L /usr/aarch64-linux-gnu "$importer" "$work/plan.txt" \
                                 "$binary" 2>&1) || status=$? ;;
                wine) line=$("$WINE" "$importer" "$(windows_path "$work/plan.txt")" \
                                 "$(windows_path "$binary")" 2>&1 | tr -d '\r' |
                             grep -v '^wine: ') || status=$? ;;
            esac
            summary+=("$id FMI $fmi $platform ($runner): $(tail -1 <<< "$line")")
            if [ "$status" -ne 0 ] || ! grep -q ': passed$' <<< "$line"; then
                failed=1
                echo "$line" >&2
            fi
        done
    done
done
log "summary"
printf '  %s\n' "${summary[@]}"
[ "$failed" = 0 ] || die "a platform's binary did not reproduce the reference (see above)"
