#!/usr/bin/env bash
# Usage: run_can_vm.sh WORK_DIR PROBE
# The CAN test VM: fetches the kernel (cached under WORK_DIR), builds the initramfs with the
# vcan and can-raw modules, candump and PROBE, boots it and leaves the console in
# WORK_DIR/console.log. Exits 77 with the reason on stdout when qemu cannot run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
work=${1:?usage}; probe=${2:?usage}
mkdir -p "$work"

if ! command -v qemu-system-x86_64 > /dev/null; then
  echo "qemu-system-x86_64 not found: scripts/setup installs qemu-system-x86"
  exit 77
fi
if ! version=$(qemu-system-x86_64 --version 2>&1); then
  echo "qemu-system-x86_64 does not run here: ${version:0:300}"
  exit 77
fi

candump=$(command -v candump) || { echo "candump not found: scripts/setup installs can-utils" >&2; exit 1; }
kroot=$("$here/fetch_kernel.sh" "$work/kernel")
"$here/make_initramfs.sh" "$kroot" "$work/can.cpio.gz" "$here/can_init.sh" \
  --modules "vcan can-raw" --binaries "$probe $candump"
"$here/boot.sh" "$kroot" "$work/can.cpio.gz" "$work/console.log" 90
