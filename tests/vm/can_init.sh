#!/bin/sh
# /init of the CAN test VM: vcan0 up, candump recording the bus, the ODrive probe against it,
# then the capture on the console between markers.
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev

echo "VM: kernel $(uname -r)"
modprobe vcan && modprobe can-raw || echo "VM: modprobe failed"
ip link add dev vcan0 type vcan && ip link set vcan0 up || echo "VM: vcan0 not up"
ip link show vcan0

candump -L vcan0 > /tmp/capture.log 2>&1 &
dump=$!
sleep 1  # candump has its socket bound before the first frame

/bin/odrive_vm_probe
echo "VM: probe exit status $?"

sleep 1
kill -INT "$dump"
wait "$dump"
echo "=== CAPTURE BEGIN ==="
cat /tmp/capture.log
echo "=== CAPTURE END ==="
poweroff -f
