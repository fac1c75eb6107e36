#!/usr/bin/env bash
# Usage: fetch_kernel.sh CACHE_DIR
# Fetches the kernel that Debian's linux-image-amd64 depends on with `apt-get download` (the
# package is unpacked with dpkg -x, never installed), runs depmod on the unpacked tree and
# prints the tree's path. Cached: a second run downloads nothing.
set -euo pipefail

cache=${1:?usage: fetch_kernel.sh CACHE_DIR}
mkdir -p "$cache"

find_package() {
  apt-cache depends linux-image-amd64 2>/dev/null |
    awk '$1 == "Depends:" && $2 ~ /^linux-image-[0-9]/ { print $2; exit }'
}
pkg=$(find_package)
if [[ -z $pkg && $(id -u) -eq 0 ]]; then
  # A machine that never ran apt-get update knows no packages yet.
  apt-get update -qq >&2
  pkg=$(find_package)
fi
[[ -n $pkg ]] || { echo "fetch_kernel: apt-cache knows no linux-image-amd64 (run apt-get update)" >&2; exit 1; }

root=$cache/$pkg
if [[ ! -f $root/.ready ]]; then
  rm -rf "$root" "$cache"/*.deb
  # apt-get download writes into the current directory.
  (cd "$cache" && apt-get download -q "$pkg" >&2)
  dpkg -x "$cache/${pkg}"_*.deb "$root"
  rm -f "$cache"/*.deb
  release=$(ls "$root/lib/modules")
  depmod -b "$root" "$release"
  touch "$root/.ready"
fi
echo "$root"
