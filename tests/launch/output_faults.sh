#!/usr/bin/env bash
# Usage: output_faults.sh FLOWSTEER WORK_DIR
# Faults in the output folder, with `flowsteer sim` run as a user runs it, each after a good run
# has written the folder:
#   full      the disk is full when the run ends;
#   readonly  the file system turns read-only during the run;
#   killed    the run is killed (SIGKILL) while its staging folder holds a half-written video.
# In each the folder keeps the good run's files, byte for byte, and gets no partial file; the
# first two fail with status 1 and a message naming the file and the reason. A staging folder
# that could not be removed (read-only) or was abandoned (killed) is removed by the next run.
# The first two mount a small tmpfs in a user and mount namespace (unshare -rm); where that is
# not allowed the script exits 77 (skipped), except under CI=true.
set -euo pipefail

flowsteer=${1:?usage}; work=${2:?usage}
rm -rf "$work"
mkdir -p "$work"

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
# A run that must succeed: flowsteer sim at 32² into the folder $1 (its progress to a log).
good_run() {
  "$flowsteer" sim --steps 40 --resolution 32 --out "$1" > /dev/null 2> "$work/good.log" ||
    fail "flowsteer sim --out $1 failed: $(cat "$work/good.log")"
}
# The folder's visible files with their checksums.
snapshot() {
  (cd "$1" && find . -path './.staging-*' -prune -o -type f -print | sort | xargs md5sum)
}
# Waits up to 20 s for a path matching the glob $1 to exist (and be non-empty with -s).
wait_for() {
  for _ in $(seq 2000); do
    # shellcheck disable=SC2086
    for path in $1; do
      [[ -s $path || ( -e $path && ${2:-} != -s ) ]] && return 0
    done
    sleep 0.01
  done
  fail "nothing matched $1 within 20 s"
}
expect_failure() {  # expect_failure LOG REASON: status 1, the reason and a file named
  local status=$1 log=$2 reason=$3
  [[ $status -eq 1 ]] || fail "exit status $status, expected 1: $(cat "$log")"
  grep -q "flowsteer: error: cannot write .*: $reason" "$log" ||
    fail "no 'cannot write FILE: $reason' in: $(cat "$log")"
}

case_killed() {
  local out=$work/killed
  good_run "$out"
  local before
  before=$(snapshot "$out")
  "$flowsteer" sim --steps 2000 --resolution 32 --video --out "$out" > /dev/null 2>&1 &
  local pid=$!
  wait_for "$out/.staging-$pid/agent_0.mp4" -s
  kill -KILL "$pid"
  { wait "$pid"; } 2> /dev/null || true
  [[ "$(snapshot "$out")" == "$before" ]] || fail "killed: the folder's files changed"
  good_run "$out"
  [[ -z "$(find "$out" -name '.staging-*')" ]] || fail "killed: the next run left the staging"
  echo "killed: the folder kept its files; the next run removed the abandoned staging folder"
}

# Runs in its own user and mount namespace, where it may mount.
namespaced_cases() {
  local disk=$work/disk
  mkdir -p "$disk"

  mount -t tmpfs -o size=1m tmpfs "$disk"
  good_run "$disk/out"
  local before status=0
  before=$(snapshot "$disk/out")
  dd if=/dev/zero of="$disk/filler" bs=4k 2> /dev/null || true
  "$flowsteer" sim --steps 60 --resolution 32 --out "$disk/out" > /dev/null 2> "$work/full.log" ||
    status=$?
  expect_failure "$status" "$work/full.log" "No space left on device"
  [[ "$(snapshot "$disk/out")" == "$before" ]] || fail "full: the folder's files changed"
  [[ -z "$(find "$disk/out" -name '.staging-*')" ]] || fail "full: a staging folder was left"
  echo "full: $(grep -o 'cannot write.*' "$work/full.log")"
  umount "$disk"

  mount -t tmpfs -o size=4m tmpfs "$disk"
  good_run "$disk/out"
  before=$(snapshot "$disk/out")
  status=0
  "$flowsteer" sim --steps 400 --resolution 32 --out "$disk/out" > /dev/null \
    2> "$work/readonly.log" &
  local pid=$!
  wait_for "$disk/out/.staging-$pid"
  mount -o remount,ro "$disk"
  wait "$pid" || status=$?
  expect_failure "$status" "$work/readonly.log" "Read-only file system"
  [[ "$(snapshot "$disk/out")" == "$before" ]] || fail "readonly: the folder's files changed"
  mount -o remount,rw "$disk"
  good_run "$disk/out"
  [[ -z "$(find "$disk/out" -name '.staging-*')" ]] || fail "readonly: the next run left one"
  echo "readonly: $(grep -o 'cannot write.*' "$work/readonly.log")"
  umount "$disk"
}

case_killed
if ! unshare --user --map-root-user --mount true 2> /dev/null; then
  [[ ${CI:-} != true ]] || fail "unshare --user --mount is not allowed here, and CI=true"
  echo "unshare --user --mount is not allowed here: the full and read-only cases are skipped"
  exit 77
fi
export -f fail good_run snapshot wait_for expect_failure namespaced_cases
flowsteer=$flowsteer work=$work unshare --user --map-root-user --mount \
  bash -euo pipefail -c namespaced_cases
