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
MODELS=(SuperTwistingObserver Pendulum TwistingController RobotObserver)
CFLAGS=(-std=c11 -Wall -Wextra -Wpedantic -Werror -O2)

log() { printf '\033[1m== %s\033[0m\n' "$*"; }
die() { echo "check_platforms.sh: $*" >&2; exit 1; }

eval "$(bash tools/dist/install_toolchains.sh)"
export WINEPREFIX WINEDEBUG=-all
FMI_INCLUDE=$("$PY" -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')
rm -rf "$OUT" && mkdir -p "$OUT"

log "building the importer for each platform"
gcc "${CFLAGS[@]}" -isystem "$FMI_INCLUDE" -o "$OUT/run_reference" tools/dist/run_reference.c -ldl -lm
aarch64-linux-gnu-gcc "${CFLAGS[@]}" -isystem "$FMI_INCLUDE" -o "$OUT/run_reference.aarch64" \
    tools/dist/run_reference.c -ldl -lm
x86_64-w64-mingw32-gcc "${CFLAGS[@]}" -static-libgcc -isystem "$FMI_INCLUDE" \
    -o "$OUT/run_reference.exe" tools/dist/run_reference.c

# Wine wants Windows paths: the Z: drive is the host's root.
windows_path() { echo "Z:$(realpath "$1" | tr / '\\')"; }

# FMI version | runner | platform folder | binary extension | importer
RUNS=(
    "2|native|linux64|so|$OUT/run_reference"
    "2|wine|win64|dll|$OUT/run_reference.exe"
    "3|native|x86_64-linux|so|$OUT/run_reference"
    "3|qemu|aarch64-linux|so|$OUT/run_reference.aarch64"
    "3|wine|x86_64-windows|dll|$OUT/run_reference.exe"
)
failed=0
summary=()
for id in "${MODELS[@]}"; do
    for fmi in 2 3; do
        fmu=$DIST/fmi$fmi/$id.fmu
        [ -f "$fmu" ] || die "$fmu missing: run ./build.sh dist"
        work=$OUT/fmi$fmi-$id
        mkdir -p "$work" && (cd "$work" && "$PY" -m zipfile -e "$OLDPWD/$fmu" .)
        "$PY" tools/dist/plan.py "$fmu" "$work/plan.txt" >/dev/null
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
