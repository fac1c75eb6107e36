#!/usr/bin/env bash
# Usage: make_initramfs.sh KERNEL_ROOT OUT.cpio INIT [--modules "m1 m2"] [--binaries "b1 b2"]
#                          [--files "/abs/f1 src=/dest"]
# (a binary named without a slash is looked up on PATH)
# Builds a busybox-static initramfs for the kernel unpacked at KERNEL_ROOT (fetch_kernel.sh):
# INIT becomes /init, the named modules and everything they depend on go under /lib/modules
# (depmod -b, so busybox's modprobe finds them), and each binary goes to /bin with the shared
# libraries ldd names, at their own paths. Each file goes to its own path (or, for src=dest, to
# dest), with the libraries ldd names where it is a dynamic executable or library: what a
# program loads at run time (plugins it dlopens, helpers it runs, their data), which ldd cannot
# see.
set -euo pipefail

kroot=${1:?usage}; out=${2:?usage}; init=${3:?usage}; shift 3
modules=""; binaries=""; files=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --modules) modules=$2; shift 2 ;;
    --binaries) binaries=$2; shift 2 ;;
    --files) files=$2; shift 2 ;;
    *) echo "make_initramfs: unknown argument $1" >&2; exit 2 ;;
  esac
done

# modprobe prints absolute paths; a relative KERNEL_ROOT would not be stripped from them.
kroot=$(cd "$kroot" && pwd)
release=$(ls "$kroot/lib/modules")
busybox=/bin/busybox
# ldd fails on a static binary; a dynamic busybox would need its libraries in the image too.
if [[ ! -x $busybox ]] || ldd "$busybox" > /dev/null 2>&1; then
  echo "make_initramfs: $busybox is not busybox-static (apt-get install busybox-static)" >&2
  exit 1
fi

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage"/{bin,dev,proc,sys,tmp,etc} "$stage/lib/modules/$release"
cp "$busybox" "$stage/bin/busybox"
for applet in $("$busybox" --list); do
  [[ $applet == busybox ]] || ln -s busybox "$stage/bin/$applet"
done
ln -s bin "$stage/sbin"

for module in $modules; do
  modprobe -d "$kroot" -S "$release" --show-depends "$module" |
    awk '$1 == "insmod" { print $2 }'
done | sort -u | while read -r path; do
  rel=${path#"$kroot"}
  mkdir -p "$stage/$(dirname "$rel")"
  cp "$path" "$stage/$rel"
done
cp "$kroot/lib/modules/$release"/modules.{order,builtin,builtin.modinfo} "$stage/lib/modules/$release/"
depmod -b "$stage" "$release"

copy_with_path() {
  mkdir -p "$stage/$(dirname "$1")"
  cp -L "$1" "$stage/$1"
}
# The shared libraries ldd lists for $1, at their own paths. Lines look like
# "libc.so.6 => /lib/x86_64-linux-gnu/libc.so.6 (0x...)" or "/lib64/ld-linux-x86-64.so.2 (0x...)".
copy_libraries() {
  ldd "$1" | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' |
    while read -r lib; do copy_with_path "$lib"; done
}
for binary in $binaries; do
  if [[ $binary != */* ]]; then
    name=$binary
    binary=$(command -v "$name") || {
      echo "make_initramfs: $name not found: scripts/setup installs what the VM tests need" >&2
      exit 1
    }
  fi
  cp "$binary" "$stage/bin/"
  copy_libraries "$binary"
done
for file in $files; do
  src=${file%%=*}
  dest=${file#*=}
  [[ -f $src ]] || {
    echo "make_initramfs: $src not found: scripts/setup installs what the VM tests need" >&2
    exit 1
  }
  mkdir -p "$stage/$(dirname "$dest")"
  cp -L "$src" "$stage/$dest"
  # ldd fails on what is not a dynamic ELF file (data, scripts): those have no libraries.
  if ldd "$src" > /dev/null 2>&1; then
    copy_libraries "$src"
  fi
done

cp "$init" "$stage/init"
chmod +x "$stage/init"
# Not compressed: the emulated CPU unpacks gzip slowly (the simulation-in-the-loop image, 480 MB,
# booted in 23 s compressed and 13 s as it is), and the host's gzip took as long again.
(cd "$stage" && find . | cpio -o -H newc --quiet) > "$out"
