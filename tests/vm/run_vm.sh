#!/usr/bin/env bash
# Usage: run_vm.sh KERNEL_CACHE WORK_DIR INIT TIMEOUT_S [--memory-mb N] [--cpus N]
#                  [--modules "m1 m2"] [--binaries "b1 b2"] [--files "/abs/f1 src=/dest"]
# A test VM: fetches the kernel (cached under KERNEL_CACHE, which every VM test shares), builds
# WORK_DIR/initramfs.cpio with INIT as /init and the modules and binaries (a name without a
# slash is looked up on PATH), boots it with N MB of memory (default 512) and N CPUs (default
# 1) for at most TIMEOUT_S
# and leaves the console in WORK_DIR/console.log. Exits 77 with the reason on stdout when qemu
# cannot run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; init=${3:?usage}; timeout_s=${4:?usage}; shift 4
memory_mb=512
cpus=1
while [[ ${1:-} == --memory-mb || ${1:-} == --cpus ]]; do
  [[ $1 == --memory-mb ]] && memory_mb=${2:?usage} || cpus=${2:?usage}
  shift 2
done
mkdir -p "$work"

if ! command -v qemu-system-x86_64 > /dev/null; then
  echo "qemu-system-x86_64 not found: scripts/setup installs qemu-system-x86"
  exit 77
fi
if ! version=$(qemu-system-x86_64 --version 2>&1); then
  echo "qemu-system-x86_64 does not run here: ${version:0:300}"
  exit 77
fi

kroot=$("$here/fetch_kernel.sh" "$kernel_cache")
# The rest of the arguments (--modules, --binaries, --files) are make_initramfs.sh's.
"$here/make_initramfs.sh" "$kroot" "$work/initramfs.cpio" "$init" "$@"
"$here/boot.sh" "$kroot" "$work/initramfs.cpio" "$work/console.log" "$timeout_s" "$memory_mb" "$cpus"
