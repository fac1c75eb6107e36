#!/usr/bin/env bash
# Usage: run_libcamera_vm.sh KERNEL_CACHE WORK_DIR PROBE
# The libcamera test VM (run_vm.sh): the vimc module, built into the cached kernel tree by
# build_vimc.sh, and PROBE, with vimc_init.sh as /init. libcamera's vimc pipeline handler
# needs its IPA module, which libcamera loads at run time (ldd does not list it): the module,
# its signature (verified, so libcamera runs it in the probe's process) and its configuration
# go in as files. The console is left in WORK_DIR/console.log; exits 77 where
# qemu cannot run at all.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; probe=${3:?usage}
"$here/build_vimc.sh" "$kernel_cache" > /dev/null
ipa=/usr/lib/x86_64-linux-gnu/libcamera
exec "$here/run_vm.sh" "$kernel_cache" "$work" "$here/vimc_init.sh" 150 \
  --modules "vimc" --binaries "$probe" \
  --files "$ipa/ipa_vimc.so $ipa/ipa_vimc.so.sign /usr/share/libcamera/ipa/vimc/vimc.conf \
$here/vm_session.sh=/lib/vm_session.sh"
