#!/usr/bin/env bash
# Usage: run_vivid_vm.sh WORK_DIR PROBE
# The V4L2 test VM: fetches the kernel (cached under WORK_DIR), builds the initramfs with the
# vivid module and PROBE, boots it and leaves the console in WORK_DIR/console.log. Exits 77 with
# the reason on stdout when qemu cannot run at all.
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

kroot=$("$here/fetch_kernel.sh" "$work/kernel")
"$here/make_initramfs.sh" "$kroot" "$work/vivid.cpio.gz" "$here/vivid_init.sh" \
  --modules "vivid" --binaries "$probe"
"$here/boot.sh" "$kroot" "$work/vivid.cpio.gz" "$work/console.log" 120
