#!/bin/sh
# Usage: browser_check.sh FLOWSTEER SUITE_DIR WORK_DIR
# The report pages in headless Chromium (browser/check_report.mjs): a run's (sim), a comparison's
# (and each controller's run page through its links), a suite's with every run kept (and each
# run's page), then a run folder that lost costs.csv, its page written again by `flowsteer
# report`, which must exit 1 and name the file on the page. Screenshots go to WORK_DIR/shots.
# Exits 77 (skipped) where Chromium, Node.js or the checker's npm package is missing, but fails
# under CI=true: scripts/setup installs them. Prints "browser_check: passed" last.
usage="usage: browser_check.sh FLOWSTEER SUITE_DIR WORK_DIR"
flowsteer=${1:?$usage}
suite=${2:?$usage}
work=${3:?$usage}
here=$(cd "$(dirname "$0")" && pwd)
chromium=${CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$chromium" ] || ! command -v node > /dev/null ||
  [ ! -d "$here/browser/node_modules/playwright-core" ]; then
  echo "browser_check: $chromium, node or browser/node_modules/playwright-core missing" \
    "(scripts/setup installs them)"
  [ "${CI:-}" = true ] && exit 1
  exit 77
fi
rm -rf "$work"
mkdir -p "$work" || exit 1
run() {
  "$@" > "$work/command.log" 2>&1 || { echo "browser_check: FAILED: $*"; cat "$work/command.log"; exit 1; }
}
run "$flowsteer" sim --scenario crossing --resolution 32 --out "$work/run"
run "$flowsteer" compare --scenario crossing --steps 60 --resolution 32 \
  --controllers vision,geometric --out "$work/compare"
run "$flowsteer" eval suite "$suite/crossing_45.xml" "$suite/circle_4.xml" --resolution 32 \
  --steps 100 --keep-runs all --jobs 2 --out "$work/suite"
export CHROMIUM="$chromium"
node "$here/browser/check_report.mjs" "$work/shots" "$work/run/report.html" \
  "$work/compare/report.html" "$work/suite/report.html" || exit 1

cp -r "$work/run" "$work/broken"
rm "$work/broken/costs.csv"
"$flowsteer" report "$work/broken" > "$work/report.log" 2>&1
status=$?
if [ "$status" -ne 1 ] || ! grep -q "could not read .*costs.csv" "$work/report.log"; then
  echo "browser_check: FAILED: flowsteer report on a folder without costs.csv exited $status:"
  cat "$work/report.log"
  exit 1
fi
node "$here/browser/check_report.mjs" "$work/shots" "$work/broken/report.html" \
  --expect-problem costs.csv || exit 1
echo "browser_check: passed"
