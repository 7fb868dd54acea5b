#!/usr/bin/env bash
# Every figure of the "peers and scale" tables on a ray tracing GPU (written for the H200), in one go:
#   1. the paper suite (Table 2 / Table 3 layouts, every technique incl. rt) on every view of Sponza
#      and the procedural scenes, 1080p/IZB 1024² and 4K/IZB 2048², 1 and 32 spp;
#   2. scaling: Sponza x1, x4, x16, x64, x192 (66k .. 12.8M triangles), every technique, 720p, 1080p, 4K;
#   3. rt (and izb+csm) against Embree on every test view at 1 and 32 spp, 1080p;
#   4. the rt GPU tests (validation layer on);
#   5. the plots (when python3-matplotlib is installed).
# usage: tests/bench/suite_gpu.sh [OUT_DIR]   (default suite_gpu_out; run from the repository root
# after building). Logs of each step are in OUT_DIR/*.log; a failed step is reported and the rest run.
set -uo pipefail
cd "$(dirname "$0")/../.."
out=${1:-suite_gpu_out}
mkdir -p "$out"
bench=build/bin/shadow_bench
sponza=../shared/content/sponza/sponza.gltf
[[ -f $sponza ]] || { echo "suite_gpu: $sponza not found" >&2; exit 1; }
[[ -x $bench ]] || { echo "suite_gpu: build first ($bench missing)" >&2; exit 1; }
failed=()
step() {  # step NAME COMMAND...: runs, logs, times
  local name=$1; shift
  local t0=$SECONDS
  if "$@" >"$out/$name.log" 2>&1; then echo "suite_gpu: $name ok ($((SECONDS - t0)) s)"
  else echo "suite_gpu: $name FAILED ($((SECONDS - t0)) s), see $out/$name.log"; failed+=("$name"); fi
}
{ nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null; date -u; git rev-parse --short HEAD; } \
  >"$out/environment.txt"

step paper "$bench" --suite paper --scene "$sponza,contact,atrium,foliage" --spp 1,32 --frames 20 --warmup 5 \
  --out "$out/paper"
step scaling "$bench" --suite paper --scene "$sponza" --views 1 --instances 1,4,16,64,192 --spp 1 \
  --sizes 1280x720:1024,1920x1080:1024,3840x2160:2048 --frames 10 --warmup 3 --out "$out/scaling"
mkdir -p "$out/reference"
reference_views() {
  local status=0
  for sv in "$sponza:0" "$sponza:1" contact:0 contact:1 atrium:0 atrium:1 foliage:0 foliage:1; do
    for spp in 1 32; do
      local scene=${sv%:*} view=${sv##*:}
      "$bench" --scene "$scene" --view "$view" --size 1920x1080 --izb 1024 --spp "$spp" --mode rt,izb+csm \
        --frames 5 --warmup 2 --reference --json "$out/reference/$(basename "$scene" .gltf)_v${view}_spp$spp.json" \
        || status=1
    done
  done
  return $status
}
step reference reference_views
step rt_tests env ENGINE_VALIDATION=1 build/bin/gpu_tests --gtest_filter='*RayTraced*'
# Debian's matplotlib belongs to /usr/bin/python3 (a python3 earlier on PATH may not see it).
python=
for p in python3 /usr/bin/python3; do "$p" -c 'import matplotlib' 2>/dev/null && { python=$p; break; }; done
if [[ -n $python ]]; then
  step plots "$python" tests/bench/plot_suite.py "$out/plots" "$out/paper/suite.json" "$out/scaling/suite.json"
else
  echo "suite_gpu: python3-matplotlib missing; plot later with tests/bench/plot_suite.py"
fi
echo "suite_gpu: results in $out (paper/suite.md, scaling/suite.md, reference/*.json, plots/)"
((${#failed[@]} == 0)) || { echo "suite_gpu: failed steps: ${failed[*]}"; exit 1; }
