#!/bin/sh
# /init of the V4L2 test VM: the vivid driver loaded, its nodes listed, then the V4L2 probe
# (tests/vm/v4l2_vm_probe.cpp) against them; its "PROBE" lines go to the console.
. /lib/vm_session.sh
vm_mount

echo "VM: kernel $(uname -r)"
modprobe vivid || echo "VM: modprobe vivid failed"
for node in /sys/class/video4linux/*; do
  echo "VM: $(basename "$node"): $(cat "$node/name")"
done

run_probe /bin/v4l2_vm_probe
