#!/usr/bin/env bash
# Usage: run_can_vm.sh KERNEL_CACHE WORK_DIR PROBE
# The CAN test VM (run_vm.sh): the vcan and can-raw modules, candump and PROBE, with
# can_init.sh as /init. The console is left in WORK_DIR/console.log; exits 77 where qemu cannot
# run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; probe=${3:?usage}
exec "$here/run_vm.sh" "$kernel_cache" "$work" "$here/can_init.sh" 90 \
  --modules "vcan can-raw" --binaries "$probe candump" \
  --files "$here/vm_session.sh=/lib/vm_session.sh"
