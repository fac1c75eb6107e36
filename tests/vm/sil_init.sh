#!/bin/sh
# /init of the simulation-in-the-loop test VM: vivid with one HDMI input and one HDMI output
# (what flowsteer sil loops), vcan0 with candump recording it, then the probe
# (tests/vm/sil_vm_probe.cpp), which runs /bin/flowsteer sil; the capture goes to the console
# between markers.
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mkdir -p /tmp && mount -t tmpfs tmp /tmp

echo "VM: kernel $(uname -r), $(grep -c ^processor /proc/cpuinfo) CPUs"
modprobe vivid n_devs=1 node_types=0x101 num_inputs=1 input_types=0x3 num_outputs=1 \
  output_types=0x1 || echo "VM: modprobe vivid failed"
modprobe vcan && modprobe can-raw || echo "VM: modprobe vcan failed"
ip link add dev vcan0 type vcan && ip link set vcan0 up || echo "VM: vcan0 not up"

candump -L vcan0 > /tmp/capture.log 2>&1 &
dump=$!
sleep 1  # candump has its socket bound before the first frame

/bin/sil_vm_probe
echo "VM: probe exit status $?"

kill -INT "$dump" 2> /dev/null
wait "$dump"
echo "=== CAPTURE BEGIN ==="
cat /tmp/capture.log
echo "=== CAPTURE END ==="
poweroff -f
