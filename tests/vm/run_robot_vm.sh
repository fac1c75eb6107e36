#!/usr/bin/env bash
# Usage: run_robot_vm.sh KERNEL_CACHE WORK_DIR PROBE FLOWSTEER
# The robot test VM (run_vm.sh): vivid, vcan and can-raw, candump, PROBE and the flowsteer
# binary, with robot_init.sh as /init. flowsteer brings its whole set of libraries (about
# 300 MB unpacked), so the VM gets 1.5 GB. The console is left in WORK_DIR/console.log; exits 77
# where qemu cannot run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; probe=${3:?usage}; flowsteer=${4:?usage}
exec "$here/run_vm.sh" "$kernel_cache" "$work" "$here/robot_init.sh" 240 --memory-mb 1536 \
  --modules "vivid vcan can-raw" --binaries "$probe $flowsteer candump" \
  --files "$here/vm_session.sh=/lib/vm_session.sh"
