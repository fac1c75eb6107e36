#!/bin/sh
# /init of the libcamera test VM: the vimc driver loaded (built by build_vimc.sh), its media
# and video nodes listed, then the libcamera probe (tests/vm/libcamera_vm_probe.cpp); its
# "PROBE" lines go to the console.
. /lib/vm_session.sh
vm_mount

echo "VM: kernel $(uname -r)"
modprobe vimc || echo "VM: modprobe vimc failed"
# libcamera enumerates devices through libudev and takes only those udev has initialized,
# which it tells by their entry in udev's database; no udevd runs here, so an empty entry per
# media and video node stands in for the one it would write.
mkdir -p /run/udev/data
for node in /sys/bus/media/devices/* /sys/class/video4linux/*; do
  echo "VM: $(basename "$node"): $(cat "$node/model" "$node/name" 2> /dev/null)"
  : > "/run/udev/data/c$(cat "$node/dev")"
done

run_probe /bin/libcamera_vm_probe
