#!/usr/bin/env bash
# Usage: fetch_kernel.sh CACHE_DIR
# Unpacks the kernel image kernel_packages.sh chooses (the newest whose headers, kbuild and
# source Debian serves too, so that build_vimc.sh can build for it) into
# CACHE_DIR/PACKAGE_VERSION with dpkg -x (never installed), runs depmod on the tree and prints
# its path. The .deb comes through deb_cache.sh's cache, which outlives the build folder. The
# whole choice goes into the tree's .packages, for build_vimc.sh: one choice for both. Cached: a
# second run unpacks nothing; a tree of a kernel no longer chosen is replaced.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
source "$here/deb_cache.sh"
cache=${1:?usage: fetch_kernel.sh CACHE_DIR}
mkdir -p "$cache"
# Every build folder on the machine shares the cache, and two test runs may use it at once: one
# writer at a time. build_vimc.sh, which calls this, holds the lock already.
if [[ -z ${FLOWSTEER_VM_KERNEL_LOCKED:-} ]]; then
  exec 9>> "$cache/.lock"
  flock 9
fi

choice=$("$here/kernel_packages.sh")
read -r _ pkg version <<< "$(grep '^image ' <<< "$choice")"
root=$cache/${pkg}_$version
if [[ ! -f $root/.ready ]]; then
  # Kernels no longer chosen (an unpacked one takes about 400 MB), and what a run killed midway
  # left.
  rm -rf "$cache"/linux-image-*
  deb=$(deb_fetch "$pkg" "$version")
  dpkg -x "$deb" "$root"
  release=$(ls "$root/lib/modules")
  depmod -b "$root" "$release"
  touch "$root/.ready"
fi
# Written on every run: the choice of the other packages may move while the image stays.
echo "$choice" > "$root/.packages.new"
mv "$root/.packages.new" "$root/.packages"
echo "$root"
