#!/bin/sh
# Usage: expect_failure.sh MUST_NOT_EXIST EXPECTED_TEXT COMMAND [ARG...]
# Passes when COMMAND exits non-zero, says EXPECTED_TEXT and leaves MUST_NOT_EXIST unwritten.
absent=$1
expected=$2
shift 2
output=$("$@" 2>&1)
status=$?
printf '%s\n' "$output"
if [ "$status" -eq 0 ]; then
  echo "expect_failure: the command succeeded"
  exit 1
fi
case $output in
  *"$expected"*) ;;
  *) echo "expect_failure: the output lacks '$expected'"; exit 1 ;;
esac
if [ -e "$absent" ]; then
  echo "expect_failure: $absent was written"
  exit 1
fi
