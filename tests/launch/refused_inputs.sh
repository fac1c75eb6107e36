#!/bin/sh
# Usage: refused_inputs.sh FLOWSTEER WORK_DIR
# Files that parse but mean nothing, as a user writes them: each is refused with exit 1 and
# "FILE:LINE:COLUMN: FIELD: must be from MIN to MAX UNIT, got VALUE", naming the field the file
# has, and `sim` leaves no output folder behind. Prints "refused_inputs: passed" last.
flowsteer=${1:?usage: refused_inputs.sh FLOWSTEER WORK_DIR}
work=${2:?usage: refused_inputs.sh FLOWSTEER WORK_DIR}
rm -rf "$work"
mkdir -p "$work" || exit 1
failures=0

scenario() {
  cat <<EOF
name: t
step_s: 0.05
duration_s: 2
camera: {resolution: 32, hfov_deg: 120, height_m: 1.6}
agents:
  - {name: a, start: [0, 0], heading_deg: 0, goal: [3, 0], preferred_speed_mps: 1.0}
EOF
}

launch() {
  cat <<EOF
camera: {type: replay, replay: {path: video.mp4}}
drive:
  type: sim
  loop_rate_hz: 50
  limits: {max_speed_mps: 0.5, max_accel_mps2: 0.5, max_turn_rate: 1.0}
  watchdog: {timeout_s: 0.3, ramp_s: 0.1}
perception: {height_m: 0.35}
EOF
}

# expect NAME COMMAND SED EXPECTED: the file made by SED on its template, run by COMMAND (sim or
# run), must fail with EXPECTED; sim must not leave its --out folder.
expect() {
  name=$1; command=$2; edit=$3; expected=$4
  file=$work/$name.yaml
  if [ "$command" = sim ]; then scenario; else launch; fi | sed "$edit" > "$file"
  if [ "$command" = sim ]; then
    output=$($flowsteer sim "$file" --out "$work/$name.out" 2>&1)
  else
    output=$($flowsteer run "$file" 2>&1)
  fi
  status=$?
  if [ "$status" -ne 1 ] || ! printf '%s' "$output" | grep -q -F -- "$expected"; then
    echo "FAIL $name: expected exit 1 and '$expected', got exit $status: $output"
    failures=$((failures + 1))
  elif [ -e "$work/$name.out" ]; then
    echo "FAIL $name: $work/$name.out was created"
    failures=$((failures + 1))
  else
    echo "ok $name: $output"
  fi
}

expect resolution sim 's/resolution: 32/resolution: 100000/' \
  "4:22: camera.resolution: must be from 8 to 4096 px, got 100000"
expect duration sim 's/duration_s: 2/duration_s: 1e9/' \
  "3:13: duration_s: must be from 0.001 to 3600 s, got 1000000000"
expect far_start sim 's/start: \[0, 0\]/start: [1e30, 0]/' \
  "agents[0].start[0]: must be from -1000 to 1000 m, got 1e+30"
expect long_step sim 's/step_s: 0.05/step_s: 10/' "2:9: step_s: must be from 0.001 to 1 s, got 10"
expect fast sim 's/preferred_speed_mps: 1.0/preferred_speed_mps: 1e9/' \
  "agents[0].preferred_speed_mps: must be from 0.01 to 6 m/s, got 1000000000"
expect standing sim 's/preferred_speed_mps: 1.0/preferred_speed_mps: 0/' \
  "agents[0].preferred_speed_mps: must be from 0.01 to 6 m/s, got 0"
expect lambda sim 's/^camera/controller: {lambda: 1e308}\ncamera/' \
  "controller.lambda: must be from 0.001 to 100, got 1e+308"
expect watchdog run 's/timeout_s: 0.3/timeout_s: 1e9/' \
  "drive.watchdog.timeout_s: must be from 0.02 to 2 s, got 1000000000"
expect speed_limit run 's/max_speed_mps: 0.5/max_speed_mps: 1e9/' \
  "drive.limits.max_speed_mps: must be from 0.01 to 3 m/s, got 1000000000"
expect loop_rate run 's/loop_rate_hz: 50/loop_rate_hz: 1e6/' \
  "drive.loop_rate_hz: must be from 2 to 1000 Hz, got 1000000"

if [ "$failures" -ne 0 ]; then
  exit 1
fi
echo "refused_inputs: passed"
