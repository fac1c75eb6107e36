#!/bin/sh
# Usage: expect_failure.sh MUST_NOT_EXIST EXPECTED_TEXT COMMAND [ARG...]
# Passes when COMMAND refuses its input as flowsteer documents it (exit status 1: a crash or an
# abort is no refusal), says EXPECTED_TEXT and leaves MUST_NOT_EXIST unwritten.
absent=$1
expected=$2
shift 2
output=$("$@" 2>&1)
status=$?
printf '%s\n' "$output"
if [ "$status" -ne 1 ]; then
  echo "expect_failure: exit status $status, expected 1"
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
