#!/usr/bin/env bash
# Usage: build_vimc.sh KERNEL_CACHE
# Debian's kernel is built without vimc (the virtual media controller driver that libcamera's
# vimc pipeline handler drives), so this builds it as an out-of-tree module for the kernel
# fetch_kernel.sh unpacks, from the packages kernel_packages.sh chose with that kernel (the
# tree's .packages): linux-source (for drivers/media/test-drivers/vimc only), linux-headers,
# its -common and linux-kbuild, through deb_cache.sh's cache and unpacked with dpkg -x (never
# installed). vimc.ko goes into the kernel tree's lib/modules/RELEASE/extra/ with depmod run
# again, so `--modules vimc` finds it and what it depends on. Cached: a second run downloads and
# builds nothing. Prints the tree's path, as fetch_kernel.sh does.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
source "$here/deb_cache.sh"
cache=${1:?usage: build_vimc.sh KERNEL_CACHE}
# One writer of the shared kernel cache at a time (fetch_kernel.sh).
mkdir -p "$cache"
exec 9>> "$cache/.lock"
flock 9
kroot=$(FLOWSTEER_VM_KERNEL_LOCKED=1 "$here/fetch_kernel.sh" "$cache")
# make -C changes directory: every path it is given must be absolute.
kroot=$(cd "$kroot" && pwd)
cache=$(dirname "$kroot")
release=$(ls "$kroot/lib/modules")
if [[ -f $kroot/.vimc-ready ]]; then
  echo "$kroot"
  exit 0
fi

# What a build killed midway left (under the lock, none is in progress).
rm -rf "$cache"/vimc-build.*
work=$(mktemp -d "$cache/vimc-build.XXXXXX")
trap 'rm -rf "$work"' EXIT
# ROLE PACKAGE VERSION lines; the image is unpacked already.
mapfile -t packages < <(grep -v '^image ' "$kroot/.packages")
for line in "${packages[@]}"; do
  read -r role pkg version <<< "$line"
  deb=$(deb_fetch "$pkg" "$version")
  if [[ $role == source ]]; then
    # One tarball of the whole tree: only vimc's directory is unpacked.
    dpkg-deb --fsys-tarfile "$deb" | tar -xO "./usr/src/$pkg.tar.xz" |
      tar -xJ -C "$work" "$pkg/drivers/media/test-drivers/vimc"
    vimc_src=$work/$pkg/drivers/media/test-drivers/vimc
  else
    dpkg -x "$deb" "$work/root"
  fi
done

# linux-headers-RELEASE's Makefile is one line including the -common tree's by its installed
# path (/usr/src/...); naming the unpacked copy with -f builds the same way without installing:
# the objects' tree (.config, Module.symvers) is the directory make runs in, the sources' tree
# the Makefile's own directory. CONFIG_VIDEO_VIMC=m stands in for the option Debian left unset.
headers=$work/root/usr/src/linux-headers-$release
common_makefile=$(echo "$work"/root/usr/src/linux-headers-*-common/Makefile)
make -s -C "$headers" -f "$common_makefile" M="$vimc_src" CONFIG_VIDEO_VIMC=m modules >&2
vermagic=$(modinfo -F vermagic "$vimc_src/vimc.ko")
[[ $vermagic == "$release "* ]] || {
  echo "build_vimc: vimc.ko was built for '$vermagic', not $release" >&2
  exit 1
}

# Unsigned: the kernel checks module signatures (CONFIG_MODULE_SIG) but does not require them
# (CONFIG_MODULE_SIG_FORCE is not set), so loading it only taints the kernel.
mkdir -p "$kroot/lib/modules/$release/extra"
# Without its debugging sections, as Debian installs its modules (INSTALL_MOD_STRIP).
strip --strip-debug -o "$kroot/lib/modules/$release/extra/vimc.ko" "$vimc_src/vimc.ko"
depmod -b "$kroot" "$release"
touch "$kroot/.vimc-ready"
echo "$kroot"
