#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Install the Debian packages this project needs, only those missing.
# Runs `apt-get update` once before installing anything.  blender,
# python3-numpy (its glTF importer) and gnuplot-nox serve `make bench` only
# (bench/cycles.py, the figure of bench/quality-real.sh).  Then the npm
# packages of scripts/npm/package.json, at the versions its lock file pins,
# into scripts/npm/node_modules: the Khronos glTF validator, which the tests
# and benches run over the glTF this project writes.
set -e
cd "$(dirname "$0")/.."
PKGS="build-essential pkg-config libembree-dev libopenexr-dev libyaml-dev libtinygltf-dev
nlohmann-json3-dev libstb-dev libxxhash-dev libpng-dev zlib1g-dev libcmocka-dev
clang libclang-rt-14-dev valgrind
libopenmpi-dev openmpi-bin libsdl2-dev xvfb xauth xdotool man-db groff-base openimageio-tools bsdutils help2man lowdown
qemu-user blender python3-numpy gnuplot-nox"
# Node.js and npm from Debian where the machine has none of its own
command -v npm >/dev/null 2>&1 || PKGS="$PKGS nodejs npm"
missing=""
for p in $PKGS; do
    status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    case "$status" in
        *"install ok installed"*) ;;
        *) missing="$missing $p" ;;
    esac
done
if [ -z "$missing" ]; then
    echo "deps: all packages present"
else
    echo "deps: installing$missing"
    SUDO=""
    if [ "$(id -u)" != 0 ]; then
        if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
            echo "deps: need root (or sudo) to install:$missing" >&2; exit 1
        fi
    fi
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -q
    # shellcheck disable=SC2086
    $SUDO apt-get install -y -q --no-install-recommends $missing
fi
# npm ci installs exactly what the lock file names, again whenever the lock
# file is newer than what was installed
if [ ! -f scripts/npm/node_modules/.package-lock.json ] ||
    [ scripts/npm/package-lock.json -nt scripts/npm/node_modules/.package-lock.json ]; then
    echo "deps: npm ci (scripts/npm: gltf-validator)"
    npm ci --prefix scripts/npm --no-audit --no-fund --loglevel=error
else
    echo "deps: npm packages present"
fi
