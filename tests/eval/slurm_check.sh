#!/usr/bin/env bash
# Usage: slurm_check.sh FLOWSTEER SUITE_DIR WORK_DIR
# docs/COMMANDS.md's Slurm recipe on a one-node cluster of this machine (scripts/slurm_local, in
# WORK_DIR/cluster): the job array of `flowsteer eval suite --shard` over four of the suite's
# cases and the merge submitted with it (afterok, --kill-on-invalid-dep=yes); the merged
# suite.csv and suite.txt must equal an unsharded run's, byte for byte. Then the same array with
# one shard failing: its merge must end CANCELLED within 20 s of the array's end, while a merge
# without --kill-on-invalid-dep stays pending (DependencyNeverSatisfied) until cancelled, as it
# would for ever. The cluster is stopped on every way out, and must leave no process behind.
# Exits 77 (skipped) where Slurm's or MUNGE's programs are missing, but fails under CI=true:
# scripts/setup installs them. Prints "slurm_check: passed" last.
usage="usage: slurm_check.sh FLOWSTEER SUITE_DIR WORK_DIR"
flowsteer=${1:?$usage}
suite=${2:?$usage}
work=${3:?$usage}
here=$(cd "$(dirname "$0")" && pwd)
slurm_local="$here/../../scripts/slurm_local"
# The daemons live in sbin, which a user's PATH may lack.
export PATH="$PATH:/usr/sbin:/sbin"

missing=""
for tool in munged mungekey munge slurmctld slurmd sbatch scontrol sinfo squeue scancel; do
  command -v "$tool" > /dev/null || missing="$missing $tool"
done
if [ -n "$missing" ]; then
  echo "slurm_check: missing:$missing (Debian's munge, slurmctld, slurmd and slurm-client;" \
    "scripts/setup installs them)"
  [ "${CI:-}" = true ] && exit 1
  exit 77
fi
rm -rf "$work"
mkdir -p "$work" || exit 1
# Absolute: the jobs run in folders of their own.
flowsteer="$(cd "$(dirname "$flowsteer")" && pwd)/$(basename "$flowsteer")"
suite=$(cd "$suite" && pwd) || exit 1
work=$(cd "$work" && pwd) || exit 1
cluster="$work/cluster"
export SLURM_CONF="$cluster/slurm.conf"

# Stops the cluster however the test ends; --while-alive stops it too where the test is killed
# before this trap can run (ctest's timeout).
trap '"$slurm_local" stop "$cluster"' EXIT
trap 'exit 1' INT TERM HUP

fail() {
  echo "slurm_check: FAILED: $*"
  local out
  for out in "$work"/*/slurm-*.out; do
    [ -s "$out" ] || continue
    echo "== slurm_check: $out"
    tail -n 20 "$out"
  done
  "$slurm_local" logs "$cluster"
  exit 1
}

# Where the cluster does not come up, slurm_local has printed why, with the daemons' logs.
"$slurm_local" start "$cluster" --while-alive $$ ||
  { echo "slurm_check: FAILED: scripts/slurm_local start $cluster"; exit 1; }

# Small and quick: four cases, 32 x 32 pixels, 100 steps; the recipe's flow and segmentation.
cases=("$suite/crossing_45.xml" "$suite/circle_4.xml" "$suite/oncoming_head_on.xml"
  "$suite/single_agent_turn.xml")
options=(--flow dis_medium --segmentation flow_graph_fast --resolution 32 --steps 100)

# The recipe's job script, with three shards of one CPU each (two CPUs run two at once) and
# BEFORE as a line ahead of the command.
write_job_script() { # FILE BEFORE
  cat > "$1" << EOF
#!/bin/bash
#SBATCH --job-name=flowsteer-suite
#SBATCH --array=0-2
#SBATCH --cpus-per-task=1
#SBATCH --time=00:05:00
$2
$(printf '%q ' "$flowsteer" eval suite "${options[@]}" "${cases[@]}")"\$@" \\
  --jobs "\$SLURM_CPUS_PER_TASK" --shard "\$SLURM_ARRAY_TASK_ID/\$SLURM_ARRAY_TASK_COUNT" \\
  --out "shards/\$SLURM_ARRAY_TASK_ID"
EOF
}

# sbatch ARGS... in the current folder; prints the job's id.
submit() {
  local id
  id=$(timeout 30 sbatch --parsable "$@") || return 1
  echo "${id%%;*}"
}

# The job's state, or each array task's as TASK:STATE, with the reason of a pending one.
job_states() {
  timeout 10 scontrol show job -o "$1" 2> /dev/null | awk '{
    task = ""; state = ""; reason = ""
    for (i = 1; i <= NF; i++) {
      if ($i ~ /^ArrayTaskId=/) task = substr($i, 13) ":"
      if ($i ~ /^JobState=/) state = substr($i, 10)
      if ($i ~ /^Reason=/) reason = substr($i, 8)
    }
    print task state (state == "PENDING" ? "(" reason ")" : "")
  }' | sort | tr '\n' ' ' | sed 's/ $//'
}

# Whether every record of STATES has ended.
ended() {
  local state
  [ -n "$1" ] || return 1
  for state in $1; do
    case "${state#*:}" in
      COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) ;;
      BOOT_FAIL | DEADLINE | PREEMPTED) ;;
      *) return 1 ;;
    esac
  done
}

# Waits up to LIMIT seconds for job ID to end, or with STATES, until its states are those;
# prints its states, and returns 1 where the time ran out.
wait_for() { # ID LIMIT [STATES]
  local deadline=$((SECONDS + $2)) states
  while :; do
    states=$(job_states "$1")
    if [ $# -ge 3 ]; then
      [ "$states" = "$3" ] && break
    else
      ended "$states" && break
    fi
    [ $SECONDS -lt $deadline ] || { echo "${states:-no record} after $2 s"; return 1; }
    sleep 0.5
  done
  echo "$states"
}

start=$SECONDS
mkdir -p "$work/shards_ok" && cd "$work/shards_ok" || exit 1
write_job_script suite.sbatch ""
merge_command="$(printf '%q ' "$flowsteer")eval merge shards/* --out suite"
array=$(submit suite.sbatch) || fail "sbatch suite.sbatch in $PWD"
merge=$(submit --dependency="afterok:$array" --kill-on-invalid-dep=yes --wrap "$merge_command") ||
  fail "sbatch of the merge"
states=$(wait_for "$array" 45) || fail "array $array: $states"
echo "slurm_check: array $array: $states"
[ "$states" = "0:COMPLETED 1:COMPLETED 2:COMPLETED" ] || fail "array $array: $states"
states=$(wait_for "$merge" 20) || fail "merge $merge: $states"
echo "slurm_check: merge $merge: $states ($((SECONDS - start)) s after the array's submission)"
[ "$states" = COMPLETED ] || fail "merge $merge: $states"

"$flowsteer" eval suite "${options[@]}" "${cases[@]}" --jobs 2 --out "$work/whole" \
  > "$work/whole.log" 2>&1 || { cat "$work/whole.log"; fail "the unsharded suite"; }
for file in suite.csv suite.txt; do
  if ! cmp "$work/whole/$file" "suite/$file"; then
    diff "$work/whole/$file" "suite/$file"
    fail "the merged $file differs from the unsharded run's"
  fi
done
echo "slurm_check: the merged suite.csv and suite.txt equal the unsharded run's, byte for byte"

# One shard fails: task 1 is also given a case file that does not exist, so its flowsteer exits
# 1. Beside the recipe's merge, one submitted without --kill-on-invalid-dep.
mkdir -p "$work/shard_fails" && cd "$work/shard_fails" || exit 1
write_job_script suite.sbatch \
  "[ \"\$SLURM_ARRAY_TASK_ID\" != 1 ] || set -- $(printf '%q' "$work/no_such_case.xml")"
array=$(submit suite.sbatch) || fail "sbatch suite.sbatch in $PWD"
merge=$(submit --dependency="afterok:$array" --kill-on-invalid-dep=yes --wrap "$merge_command") ||
  fail "sbatch of the merge"
stuck=$(submit --dependency="afterok:$array" --wrap "$merge_command") ||
  fail "sbatch of the merge without --kill-on-invalid-dep"
states=$(wait_for "$array" 45) || fail "array $array: $states"
echo "slurm_check: array $array, shard 1 failing: $states"
[ "$states" = "0:COMPLETED 1:FAILED 2:COMPLETED" ] || fail "array $array: $states"
ended_at=$SECONDS
states=$(wait_for "$merge" 20) || fail "merge $merge: $states, not CANCELLED"
echo "slurm_check: merge $merge (--kill-on-invalid-dep=yes): $states" \
  "($((SECONDS - ended_at)) s after the array ended)"
[ "$states" = CANCELLED ] || fail "merge $merge: $states, not CANCELLED"
states=$(wait_for "$stuck" 20 "PENDING(DependencyNeverSatisfied)") ||
  fail "merge $stuck without --kill-on-invalid-dep: $states"
echo "slurm_check: merge $stuck (without it): $states"
[ ! -e suite ] || fail "a merge ran despite the failed shard"

trap - EXIT
"$slurm_local" stop "$cluster" || fail "scripts/slurm_local stop $cluster"
echo "slurm_check: the cluster stopped, no process of it left ($SECONDS s in all)"
echo "slurm_check: passed"
