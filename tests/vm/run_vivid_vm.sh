#!/usr/bin/env bash
# Usage: run_vivid_vm.sh KERNEL_CACHE WORK_DIR PROBE
# The V4L2 test VM (run_vm.sh): the vivid module and PROBE, with vivid_init.sh as /init. The
# console is left in WORK_DIR/console.log; exits 77 where qemu cannot run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; probe=${3:?usage}
exec "$here/run_vm.sh" "$kernel_cache" "$work" "$here/vivid_init.sh" 120 \
  --modules "vivid" --binaries "$probe" --files "$here/vm_session.sh=/lib/vm_session.sh"
