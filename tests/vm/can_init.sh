#!/bin/sh
# /init of the CAN test VM: vcan0 up, candump recording the bus, the ODrive probe against it,
# then the capture on the console between markers.
. /lib/vm_session.sh
vm_mount
echo "VM: kernel $(uname -r)"
vcan_up
ip link show vcan0
run_probe_with_capture /bin/odrive_vm_probe
