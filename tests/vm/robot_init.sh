#!/bin/sh
# /init of the robot test VM: vivid (the camera), vcan0 (the CAN bus) with candump recording
# it, then the robot probe (tests/vm/robot_vm_probe.cpp), which runs /bin/flowsteer against
# them; the capture goes to the console between markers.
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev

echo "VM: kernel $(uname -r)"
modprobe vivid || echo "VM: modprobe vivid failed"
modprobe vcan && modprobe can-raw || echo "VM: modprobe vcan failed"
ip link add dev vcan0 type vcan && ip link set vcan0 up || echo "VM: vcan0 not up"

candump -L vcan0 > /tmp/capture.log 2>&1 &
dump=$!
sleep 1  # candump has its socket bound before the first frame

/bin/robot_vm_probe
echo "VM: probe exit status $?"

kill -INT "$dump" 2> /dev/null
wait "$dump"
echo "=== CAPTURE BEGIN ==="
cat /tmp/capture.log
echo "=== CAPTURE END ==="
poweroff -f
