# What the /init of each VM that tests over vcan0 shares (can_init.sh, robot_init.sh,
# sil_init.sh); copied into the VM as /lib/can_session.sh and sourced there (busybox sh).

# The kernel's filesystems, and a tmpfs for the capture.
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

# Runs PROBE with candump recording vcan0, then prints the probe's exit status and the capture
# between markers (vm_test_support.hpp and can_capture.hpp read them) and powers off.
run_probe_with_capture() {
  candump -L vcan0 > /tmp/capture.log 2>&1 &
  dump=$!
  sleep 1  # candump has its socket bound before the first frame
  "$1"
  echo "VM: probe exit status $?"
  sleep 1  # the probe's last frames reach candump
  kill -INT "$dump" 2> /dev/null
  wait "$dump"
  echo "=== CAPTURE BEGIN ==="
  cat /tmp/capture.log
  echo "=== CAPTURE END ==="
  poweroff -f
}
