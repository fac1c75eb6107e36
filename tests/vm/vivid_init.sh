#!/bin/sh
# /init of the V4L2 test VM: the vivid driver loaded, its nodes listed, then the V4L2 probe
# (tests/vm/v4l2_vm_probe.cpp) against them; its "PROBE" lines go to the console.
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev

echo "VM: kernel $(uname -r)"
modprobe vivid || echo "VM: modprobe vivid failed"
for node in /sys/class/video4linux/*; do
  echo "VM: $(basename "$node"): $(cat "$node/name")"
done

/bin/v4l2_vm_probe
echo "VM: probe exit status $?"
poweroff -f
