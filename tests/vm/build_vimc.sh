#!/usr/bin/env bash
# Usage: build_vimc.sh KERNEL_CACHE
# Debian's kernel is built without vimc (the virtual media controller driver that libcamera's
# vimc pipeline handler drives), so this builds it as an out-of-tree module for the kernel
# fetch_kernel.sh unpacks, from Debian's own packages of the same version: linux-source (for
# drivers/media/test-drivers/vimc only), linux-headers and linux-kbuild, fetched with
# `apt-get download` and unpacked with dpkg -x (never installed). vimc.ko goes into the
# kernel tree's lib/modules/RELEASE/extra/ with depmod run again, so `--modules vimc` finds it
# and what it depends on. Cached: a second run downloads and builds nothing. Prints the tree's
# path, as fetch_kernel.sh does.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
cache=${1:?usage: build_vimc.sh KERNEL_CACHE}
kroot=$("$here/fetch_kernel.sh" "$cache")
# make -C changes directory: every path it is given must be absolute.
kroot=$(cd "$kroot" && pwd)
cache=$(dirname "$kroot")
release=$(ls "$kroot/lib/modules")
if [[ -f $kroot/.vimc-ready ]]; then
  echo "$kroot"
  exit 0
fi

# The Debian version of the kernel that boots, from its own version string ("... #1 SMP
# PREEMPT_DYNAMIC Debian 6.1.192-2 (2026-11-16)"): the packages must be of exactly this one.
version=$(grep -aoE '#[0-9]+ SMP [A-Z_ ]*Debian [^ ]+' "$kroot/boot/vmlinuz-$release" |
  head -n 1 | awk '{ print $NF }')
[[ -n $version ]] || { echo "build_vimc: no Debian version in $kroot/boot/vmlinuz-$release" >&2; exit 1; }
upstream=${version%%-*}                        # 6.1.192
source_pkg=linux-source-${upstream%.*}         # linux-source-6.1
headers_pkg=linux-headers-$release
# linux-headers-RELEASE depends on the flavour-independent headers (…-common) and on
# linux-kbuild-6.1, the build's host programs (modpost, fixdep).
deps=$(apt-cache show "$headers_pkg=$version" 2>/dev/null |
  awk -F': ' '$1 == "Depends" { print $2; exit }' | tr ',' '\n' |
  awk '$1 ~ /^linux-(headers|kbuild)-/ { print $1 }')
[[ -n $deps ]] || {
  echo "build_vimc: apt-cache knows no $headers_pkg of version $version, the kernel in $kroot" \
    "(run apt-get update; if Debian has moved on, remove $kroot to fetch its current kernel)" >&2
  exit 1
}

# What a build killed midway left (the VM tests run one at a time: none is in progress).
rm -rf "$cache"/vimc-build.*
work=$(mktemp -d "$cache/vimc-build.XXXXXX")
trap 'rm -rf "$work"' EXIT
packages=()
for pkg in "$source_pkg" "$headers_pkg" $deps; do
  packages+=("$pkg=$version")
done
# apt-get download writes into the current directory.
(cd "$work" && apt-get download -q "${packages[@]}" >&2)
for pkg in "$headers_pkg" $deps; do
  dpkg -x "$work/${pkg}_"*.deb "$work/root"
done
# The source package holds one tarball of the whole tree; only vimc's directory is unpacked.
dpkg-deb --fsys-tarfile "$work/${source_pkg}_"*.deb |
  tar -xO "./usr/src/$source_pkg.tar.xz" |
  tar -xJ -C "$work" "$source_pkg/drivers/media/test-drivers/vimc"
rm -f "$work"/*.deb

# linux-headers-RELEASE's Makefile is one line including the -common tree's by its installed
# path (/usr/src/...); naming the unpacked copy with -f builds the same way without installing:
# the objects' tree (.config, Module.symvers) is the directory make runs in, the sources' tree
# the Makefile's own directory. CONFIG_VIDEO_VIMC=m stands in for the option Debian left unset.
headers=$work/root/usr/src/$headers_pkg
common_makefile=$(echo "$work"/root/usr/src/linux-headers-*-common/Makefile)
vimc_src=$work/$source_pkg/drivers/media/test-drivers/vimc
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
