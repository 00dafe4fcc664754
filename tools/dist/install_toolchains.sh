#!/usr/bin/env bash
# Installs the cross toolchains of `./build.sh dist` and the runners of
# tools/dist/check_platforms.sh, each only when missing (a second run takes a second):
#
#   Debian: gcc-aarch64-linux-gnu + libc6-dev-arm64-cross  aarch64 Linux
#           gcc-mingw-w64-x86-64                            x86_64 Windows
#           llvm (llvm-nm, llvm-objdump)                    Mach-O export tables
#           qemu-user, wine64                               running aarch64 and Windows binaries
#   PyPI:   ziglang (pinned below; `zig cc`)                x86_64 and aarch64 macOS
#
# zig goes under ${STO_TOOLS_CACHE:-$HOME/.cache/sto-tools}/ziglang-<version> (pip --target,
# with the project's .venv Python); its compiler cache and the wine prefix go there too.
# Prints the shell variables ZIG, ZIG_GLOBAL_CACHE_DIR, ZIG_LOCAL_CACHE_DIR, WINE and
# WINEPREFIX for `eval`.  Any failure stops with a message.
set -euo pipefail
cd "$(dirname "$0")/../.."

ZIGLANG_VERSION=0.14.1
CACHE=${STO_TOOLS_CACHE:-$HOME/.cache/sto-tools}
PY=.venv/bin/python
log() { printf 'install_toolchains.sh: %s\n' "$*" >&2; }
die() { printf 'install_toolchains.sh: ERROR: %s\n' "$*" >&2; exit 1; }

# command | Debian packages that provide it
NEEDED=(
    "aarch64-linux-gnu-gcc|gcc-aarch64-linux-gnu libc6-dev-arm64-cross"
    "x86_64-w64-mingw32-gcc|gcc-mingw-w64-x86-64"
    "llvm-objdump|llvm"
    "qemu-aarch64|qemu-user"
    "/usr/lib/wine/wine64|wine64"
)
missing=()
for entry in "${NEEDED[@]}"; do
    IFS='|' read -r command packages <<< "$entry"
    command -v "$command" >/dev/null 2>&1 || missing+=($packages)
done
if [ "${#missing[@]}" -gt 0 ]; then
    log "installing ${missing[*]}"
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null || die "not root with apt-get: install ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
for entry in "${NEEDED[@]}"; do
    command -v "${entry%%|*}" >/dev/null 2>&1 || die "${entry%%|*} is still missing"
done

mkdir -p "$CACHE"
CACHE=$(cd "$CACHE" && pwd)
ZIG_HOME=$CACHE/ziglang-$ZIGLANG_VERSION
if [ ! -x "$ZIG_HOME/ziglang/zig" ]; then
    log "installing ziglang $ZIGLANG_VERSION into $ZIG_HOME"
    [ -x "$PY" ] || die "no $PY: run ./build.sh fmus first"
    rm -rf "$ZIG_HOME.tmp"
    "$PY" -m pip install --quiet --disable-pip-version-check --no-deps --target "$ZIG_HOME.tmp" \
        "ziglang==$ZIGLANG_VERSION"
    mv "$ZIG_HOME.tmp" "$ZIG_HOME"
fi
mkdir -p "$CACHE/zig-cache" "$CACHE/wine"
echo "ZIG=$ZIG_HOME/ziglang/zig"
echo "ZIG_GLOBAL_CACHE_DIR=$CACHE/zig-cache"
echo "ZIG_LOCAL_CACHE_DIR=$CACHE/zig-cache"
echo "WINE=/usr/lib/wine/wine64"
echo "WINEPREFIX=$CACHE/wine"
