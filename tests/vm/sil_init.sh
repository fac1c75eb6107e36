#!/bin/sh
# /init of the simulation-in-the-loop test VM: vivid with one HDMI input and one HDMI output
# (what flowsteer sil loops), vcan0 with candump recording it, then the probe
# (tests/vm/sil_vm_probe.cpp), which runs /bin/flowsteer sil; the capture goes to the console
# between markers.
. /lib/vm_session.sh
vm_mount
echo "VM: kernel $(uname -r), $(grep -c ^processor /proc/cpuinfo) CPUs"
modprobe vivid n_devs=1 node_types=0x101 num_inputs=1 input_types=0x3 num_outputs=1 \
  output_types=0x1 || echo "VM: modprobe vivid failed"
vcan_up
run_probe_with_capture /bin/sil_vm_probe
