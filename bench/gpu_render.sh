#!/usr/bin/env bash
# The crowd's render on a machine with a GPU, in one command: crowd_bench (synthetic flow, a ring
# of agents, one thread) with the views drawn layered on the GPU, one by one on the GPU, and on
# Mesa's llvmpipe on the same machine, each at 10, 100 and 200 agents, 128² and 256².
#
#   bench/gpu_render.sh [BUILD_DIR] [STEPS]       (defaults: build, 40)
#
# The llvmpipe runs hide the GPU from EGL by naming Mesa's vendor file alone to GLVND
# (__EGL_VENDOR_LIBRARY_FILENAMES). Each run's first line names the renderer that drew it; the
# script fails when a GPU run was drawn by llvmpipe (no GPU's EGL driver found) or an llvmpipe
# run by a GPU, so that no table compares what it does not say.
set -euo pipefail

build=${1:-build}
steps=${2:-40}
bench="$build/bench/crowd_bench"
[[ -x $bench ]] || { echo "gpu_render.sh: $bench not found (scripts/build builds it)" >&2; exit 1; }
mesa_vendor=/usr/share/glvnd/egl_vendor.d/50_mesa.json
[[ -f $mesa_vendor ]] || { echo "gpu_render.sh: $mesa_vendor not found (libegl-mesa0)" >&2; exit 1; }

run() { # NAME EXPECT(gpu|llvmpipe) CROWD_BENCH_ARGS...
  local name=$1 expect=$2 output renderer
  shift 2
  echo "== $name"
  output=$("$@" --steps "$steps" --agents 10,100,200 --resolutions 128,256 --threads 1)
  echo "$output"
  renderer=$(head -n 1 <<< "$output")
  if [[ $expect == gpu && $renderer == *llvmpipe* ]] ||
    [[ $expect == llvmpipe && $renderer != *llvmpipe* ]]; then
    echo "gpu_render.sh: $name was to run on $expect, but $renderer" >&2
    exit 1
  fi
}

run "GPU, views layered" gpu "$bench" --submission layered
run "GPU, views one by one" gpu "$bench" --submission per_view
run "llvmpipe" llvmpipe env __EGL_VENDOR_LIBRARY_FILENAMES="$mesa_vendor" "$bench"
