#!/bin/sh
# Usage: option_bounds.sh FLOWSTEER
# Every bounded option of every command, found in the command's help ("--resolution INT:from 8 to
# 4096 px", written from the same bound as the file's field, base/quantity_bounds.hpp): each end
# is accepted and one step beyond each end is refused with exit 2 and "OPTION: must be from MIN
# to MAX UNIT, got VALUE". An accepted value is shown by a run that then fails on another
# argument given to stop it (a rule that does not exist, a file that does not): the run gets as
# far as that argument's own error, so nothing runs.
# Prints "option_bounds: passed" last when every check holds.
flowsteer=${1:?usage: option_bounds.sh FLOWSTEER}
failures=0
checked=0

# check COMMAND OPTION VALUE COUNT INSIDE MIN MAX STOPPED STOPPER...: OPTION given VALUE (COUNT
# times, for an option that takes two numbers); an INSIDE value must get as far as the STOPPED
# text, the STOPPER argument's error.
check() {
  command=$1; option=$2; value=$3; count=$4; inside=$5; min=$6; max=$7; stopped=$8; shift 8
  values=$value
  [ "$count" -eq 2 ] && values="$value $value"
  # shellcheck disable=SC2086  # the command's words, the option's values
  output=$($flowsteer $command "$option" $values "$@" 2>&1)
  status=$?
  checked=$((checked + 1))
  if [ "$inside" = yes ]; then
    if ! printf '%s' "$output" | grep -q -F -- "$stopped"; then
      echo "FAIL: $command $option $values: did not get as far as '$stopped' (exit $status): $output"
      failures=$((failures + 1))
    fi
  elif [ "$status" -ne 2 ] ||
    ! printf '%s' "$output" | grep -q -F -- "$option: must be from $min to $max"; then
    echo "FAIL: $command $option $value: expected exit 2 and '$option: must be from $min to $max', got exit $status: $output"
    failures=$((failures + 1))
  fi
}

# walk COMMAND STOPPED STOPPER...: every option whose help gives a bound.
walk() {
  command=$1; stopped=$2; shift 2
  # shellcheck disable=SC2086
  $flowsteer $command --help | awk '
    match($0, /^ +(-[a-z],)?--[a-z-]+ (INT|FLOAT)[ .]*:from [^ ]+ to [^ ]+/) {
      text = substr($0, RSTART, RLENGTH)
      sub(/^ +(-[a-z],)?/, "", text)
      split(text, word, /[ :]+/)
      # word: option, type, ..., "from", min, "to", max
      n = 0; for (k in word) n++
      print word[1], word[2], word[n - 2], word[n], (index($0, " x 2") > 0 ? 2 : 1)
    }' > "${TMPDIR:-/tmp}/option_bounds.$$"
  while read -r option type min max count; do
    for end in min max; do
      if [ "$end" = min ]; then bound=$min; sign=-1; else bound=$max; sign=1; fi
      beyond=$(awk -v b="$bound" -v s="$sign" -v t="$type" 'BEGIN {
        step = (t == "INT") ? 1 : ((b < 0 ? -b : b) * 1e-6 > 1e-9 ? (b < 0 ? -b : b) * 1e-6 : 1e-9)
        printf "%.17g", b + s * step }')
      check "$command" "$option" "$bound" "$count" yes "$min" "$max" "$stopped" "$@"
      check "$command" "$option" "$beyond" "$count" no "$min" "$max" "$stopped" "$@"
    done
  done < "${TMPDIR:-/tmp}/option_bounds.$$"
  rm -f "${TMPDIR:-/tmp}/option_bounds.$$"
}

walk sim "unknown rule 'nowhere'" --arrival nowhere
walk compare "unknown rule 'nowhere'" --controllers vision --arrival nowhere
walk "eval suite" "unknown rule 'nowhere'" --arrival nowhere
walk "eval robustness" "unknown rule 'nowhere'" --arrival nowhere
walk run "cannot open the launch file" /nonexistent/launch.yaml
walk replay "cannot open video" /nonexistent/video.mp4
walk demo "cannot open the scene file" --scene /nonexistent/scene.yaml
walk sil "unknown scenario" /nonexistent/scenario.yaml /nonexistent/launch.yaml --robot a

echo "option_bounds: $checked checks, $failures failed"
# 19 bounded options, four checks each: fewer means an option lost its bound (or its help line).
if [ "$failures" -ne 0 ] || [ "$checked" -lt 76 ]; then
  exit 1
fi
echo "option_bounds: passed"
