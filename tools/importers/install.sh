#!/usr/bin/env bash
# Installs the independent FMI importers that tools/importers/check.py runs on
# every FMU in build/fmus (fmpy itself comes with the project's .venv, made by build.sh):
#
#   FMI4j   info.laht.fmi4j:fmi-import 0.38.0 from Maven Central, and the driver
#           tools/importers/fmi4j/src/main/java/Fmi4jDriver.java compiled against it
#   fmi-sim the Rust crate fmi-sim 0.7.0, `cargo install --locked` (needs libclang-dev)
#
# Everything goes under ${STO_TOOLS_CACHE:-$HOME/.cache/sto-tools}:
#   m2/                 Maven local repository
#   fmi4j/lib/          the FMI4j jars and their runtime dependencies
#   fmi4j/classes/      the compiled driver; fmi4j/stamp = hash of its sources
#   cargo/bin/fmi-sim   the fmi-sim binary (cargo --root)
# A second run finds both and only checks them (a few seconds).
#
# Debian packages are installed with apt-get when missing: libclang-dev (only when
# fmi-sim has to be built), and openjdk-17-jdk-headless / maven when java, javac or
# mvn is missing. Rust (cargo) must already be installed (rustup): Debian's cargo is
# too old for fmi-sim 0.7.0.
#
# Any failure stops the script with a message and a non-zero exit status; nothing is
# skipped silently.
set -euo pipefail

HERE=$(cd "$(dirname "$0")" && pwd)
CACHE=${STO_TOOLS_CACHE:-$HOME/.cache/sto-tools}
FMI_SIM_VERSION=0.7.0
FMI4J_DIR=$HERE/fmi4j

log() { printf 'install.sh: %s\n' "$*"; }
die() { printf '\ninstall.sh: ERROR: %s\n' "$*" >&2; exit 1; }
trap 'die "command failed (exit $?) at line $LINENO: $BASH_COMMAND"' ERR

started=$SECONDS
mkdir -p "$CACHE"
CACHE=$(cd "$CACHE" && pwd)
log "cache: $CACHE"

# ---- Debian packages -----------------------------------------------------------------
apt_updated=0
apt_install() {
    local sudo=()
    if [ "$(id -u)" != 0 ]; then
        command -v sudo >/dev/null || die "need root (or sudo) to apt-get install $*"
        sudo=(sudo)
    fi
    command -v apt-get >/dev/null || die "apt-get not found: install $* by hand"
    if [ $apt_updated = 0 ]; then
        log "apt-get update"
        "${sudo[@]}" apt-get update -qq || die "apt-get update failed"
        apt_updated=1
    fi
    log "apt-get install $*"
    DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "$@" \
        >/dev/null || die "apt-get install $* failed"
}
have_deb() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

# ---- FMI4j and the driver --------------------------------------------------------------
missing=()
command -v java >/dev/null || missing+=(openjdk-17-jdk-headless)
command -v javac >/dev/null || missing+=(openjdk-17-jdk-headless)
command -v mvn >/dev/null || missing+=(maven)
if [ ${#missing[@]} -gt 0 ]; then
    apt_install $(printf '%s\n' "${missing[@]}" | sort -u)
fi
java_major=$(javac -version 2>&1 | sed -n 's/^javac \([0-9]*\).*/\1/p')
[ -n "$java_major" ] && [ "$java_major" -ge 11 ] || die "javac >= 11 needed (found: $(javac -version 2>&1))"

stamp=$(cat "$FMI4J_DIR/pom.xml" "$FMI4J_DIR/src/main/java/Fmi4jDriver.java" "$FMI4J_DIR/log4j.properties" \
        <(javac -version 2>&1) | sha256sum | cut -d' ' -f1)
out=$CACHE/fmi4j
if [ -f "$out/stamp" ] && [ "$(cat "$out/stamp")" = "$stamp" ] && [ -f "$out/classes/Fmi4jDriver.class" ]; then
    log "FMI4j driver: up to date ($out)"
else
    t0=$SECONDS
    log "FMI4j: fetching info.laht.fmi4j:fmi-import and its runtime dependencies (Maven repository $CACHE/m2)"
    rm -rf "$out" && mkdir -p "$out"
    if ! mvn -B -q -Dstyle.color=never -Dmaven.repo.local="$CACHE/m2" -f "$FMI4J_DIR/pom.xml" \
            dependency:copy-dependencies -DincludeScope=runtime -DoutputDirectory="$out/lib" \
            > "$CACHE/mvn.log" 2>&1; then
        tail -40 "$CACHE/mvn.log" >&2
        die "mvn could not fetch info.laht.fmi4j:fmi-import (log above and in $CACHE/mvn.log)"
    fi
    ls "$out"/lib/fmi-import-*.jar >/dev/null 2>&1 || die "mvn ran but $out/lib has no fmi-import jar"
    log "FMI4j: compiling the driver"
    mkdir -p "$out/classes"
    javac --release "$java_major" -Xlint:all,-path -Werror -d "$out/classes" -cp "$out/lib/*" \
        "$FMI4J_DIR/src/main/java/Fmi4jDriver.java" || die "javac failed on Fmi4jDriver.java"
    cp "$FMI4J_DIR/log4j.properties" "$out/"
    echo "$stamp" > "$out/stamp"
    log "FMI4j driver: built in $((SECONDS - t0)) s ($out)"
fi
# The driver must start and find FMI4j's classes and native library.
check=$(java -cp "$out/classes:$out/lib/*" Fmi4jDriver --check 2>&1) || die "the FMI4j driver does not start: $check"
log "$check"

# ---- fmi-sim ---------------------------------------------------------------------------
fmi_sim=$CACHE/cargo/bin/fmi-sim
# `fmi-sim --version` prints "Error: fmi-sim 0.7.0" (and a backtrace) on stderr and exits 1.
fmi_sim_version() { "$fmi_sim" --version 2>&1 | grep -o -m1 'fmi-sim [0-9][0-9.]*' || true; }
if [ -x "$fmi_sim" ] && [ "$(fmi_sim_version)" = "fmi-sim $FMI_SIM_VERSION" ]; then
    log "fmi-sim $FMI_SIM_VERSION: up to date ($fmi_sim)"
else
    command -v cargo >/dev/null || die "cargo not found: install Rust with rustup (Debian's cargo is too old for fmi-sim $FMI_SIM_VERSION)"
    have_deb libclang-dev || apt_install libclang-dev
    t0=$SECONDS
    log "fmi-sim: cargo install --locked fmi-sim --version $FMI_SIM_VERSION --root $CACHE/cargo (several minutes on 2 cores)"
    cargo install --locked fmi-sim --version "$FMI_SIM_VERSION" --root "$CACHE/cargo" \
        || die "cargo install fmi-sim $FMI_SIM_VERSION failed (see the cargo output above)"
    [ -x "$fmi_sim" ] || die "cargo install succeeded but there is no $fmi_sim"
    got=$(fmi_sim_version)
    [ "$got" = "fmi-sim $FMI_SIM_VERSION" ] || die "installed fmi-sim reports '$got', expected 'fmi-sim $FMI_SIM_VERSION'"
    log "fmi-sim $FMI_SIM_VERSION: built in $((SECONDS - t0)) s ($fmi_sim)"
fi

log "done in $((SECONDS - started)) s: FMI4j driver $out, fmi-sim $fmi_sim"
log "next: .venv/bin/python -m tools.importers.check"
