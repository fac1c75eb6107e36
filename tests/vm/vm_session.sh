# What the /init scripts of the test VMs share (can_init.sh, robot_init.sh, sil_init.sh,
# vivid_init.sh, vimc_init.sh): copied into each VM as /lib/vm_session.sh and sourced there
# (busybox sh).

# The kernel's filesystems, and a tmpfs for what the probes write.
vm_mount() {
  mount -t proc proc /proc
  mount -t sysfs sys /sys
  mount -t devtmpfs dev /dev
  mkdir -p /tmp && mount -t tmpfs tmp /tmp
}

# vcan0 up, for the drives and candump.
vcan_up() {
  modprobe vcan && modprobe can-raw || echo "VM: modprobe vcan failed"
  ip link add dev vcan0 type vcan && ip link set vcan0 up || echo "VM: vcan0 not up"
}

# Runs PROBE, prints its exit status (vm_test_support.hpp reads it) and powers off.
run_probe() {
  "$1"
  echo "VM: probe exit status $?"
  poweroff -f
}

# Runs PROBE with candump recording vcan0, then prints the probe's exit status and the capture
# between markers (can_capture.hpp reads them) and powers off. candump has a second before the
# probe and one after it: its socket is bound before the first frame, and the last frames reach
# it before it is stopped.
run_probe_with_capture() {
  candump -L vcan0 > /tmp/capture.log 2>&1 &
  dump=$!
  sleep 1
  "$1"
  echo "VM: probe exit status $?"
  sleep 1
  kill -INT "$dump" 2> /dev/null
  wait "$dump"
  echo "=== CAPTURE BEGIN ==="
  cat /tmp/capture.log
  echo "=== CAPTURE END ==="
  poweroff -f
}
