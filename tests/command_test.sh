#!/bin/sh
# Usage: command_test.sh [--exit N] [--absent PATH] [--before SHELL] [--then SHELL] [--stdout FILE]
#                       -- COMMAND [ARG...]
# Runs COMMAND as a user would and prints what it says (stdout and stderr together). Passes, and
# prints "command_test: passed" last, when it exits with N (default 0: a crash or an abort is
# neither success nor a refusal), PATH does not exist afterwards (a refused input writes
# nothing) and the SHELL command of --then (which may print what the command wrote) succeeds.
# --before runs a SHELL command first (to clear an earlier run's folder); --stdout keeps what the
# command prints on stdout in FILE too (for --then to check). ctest matches the
# expected text and this last line together (flowsteer_command_test, tests/CMakeLists.txt).
expected_status=0
absent=
before=
then=
stdout_file=
while [ "$#" -gt 0 ]; do
  case $1 in
    --exit) expected_status=$2; shift 2 ;;
    --absent) absent=$2; shift 2 ;;
    --before) before=$2; shift 2 ;;
    --then) then=$2; shift 2 ;;
    --stdout) stdout_file=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "command_test: unknown option $1"; exit 2 ;;
  esac
done
if [ -n "$before" ]; then
  sh -c "$before" || { echo "command_test: --before failed: $before"; exit 1; }
fi
if [ -n "$stdout_file" ]; then
  "$@" > "$stdout_file"
  status=$?
  cat "$stdout_file"
else
  "$@" 2>&1
  status=$?
fi
if [ "$status" -ne "$expected_status" ]; then
  echo "command_test: exit status $status, expected $expected_status"
  exit 1
fi
if [ -n "$absent" ] && [ -e "$absent" ]; then
  echo "command_test: $absent was written"
  exit 1
fi
if [ -n "$then" ]; then
  sh -c "$then" 2>&1 || { echo "command_test: --then failed: $then"; exit 1; }
fi
echo "command_test: passed"
