#!/bin/sh
# /init of the robot test VM: vivid (the camera), vcan0 (the CAN bus) with candump recording
# it, then the robot probe (tests/vm/robot_vm_probe.cpp), which runs /bin/flowsteer against
# them; the capture goes to the console between markers.
. /lib/vm_session.sh
vm_mount
echo "VM: kernel $(uname -r)"
modprobe vivid || echo "VM: modprobe vivid failed"
vcan_up
run_probe_with_capture /bin/robot_vm_probe
