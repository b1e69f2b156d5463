#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Install the Debian packages this project needs, only those missing.
# Runs `apt-get update` once before installing anything.
set -e
PKGS="build-essential pkg-config libembree-dev libopenexr-dev libyaml-dev libtinygltf-dev
nlohmann-json3-dev libstb-dev libxxhash-dev libpng-dev zlib1g-dev libcmocka-dev
clang libclang-rt-14-dev valgrind
libopenmpi-dev openmpi-bin libsdl2-dev xvfb xauth xdotool man-db groff-base openimageio-tools bsdutils help2man lowdown
qemu-user"
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
    exit 0
fi
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
