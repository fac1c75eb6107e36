#!/usr/bin/env bash
# Usage: run_sil_vm.sh KERNEL_CACHE WORK_DIR PROBE FLOWSTEER
# The simulation-in-the-loop test VM (run_vm.sh): vivid, vcan and can-raw, candump, PROBE and
# the flowsteer binary with Mesa's software renderer (EGL's vendor file, libEGL_mesa and
# swrast_dri, which are loaded at run time, not linked), the test's scenario and launch file
# under /sil, with sil_init.sh as /init. Two emulated CPUs, one for the simulator and one for
# the robot, and 3 GB for the image (about 450 MB unpacked). Exits 77 where qemu cannot run.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
kernel_cache=${1:?usage}; work=${2:?usage}; probe=${3:?usage}; flowsteer=${4:?usage}
lib=/usr/lib/x86_64-linux-gnu
exec "$here/run_vm.sh" "$kernel_cache" "$work" "$here/sil_init.sh" 300 --memory-mb 3072 --cpus 2 \
  --modules "vivid vcan can-raw" --binaries "$probe $flowsteer candump" \
  --files "/usr/share/glvnd/egl_vendor.d/50_mesa.json $lib/libEGL_mesa.so.0 \
$lib/dri/swrast_dri.so $here/sil/scenario.yaml=/sil/scenario.yaml \
$here/sil/launch.yaml=/sil/launch.yaml $here/vm_session.sh=/lib/vm_session.sh"
