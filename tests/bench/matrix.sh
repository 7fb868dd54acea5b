#!/usr/bin/env bash
# Re-runs every benchmark figure BENCHMARKS.md quotes for a device and writes the JSON files into
# DIR (default bench_results/). Usage: tests/bench/matrix.sh [DIR] [--device gpu|lavapipe]
# On lavapipe the sizes are those the issues name; expect about ten minutes on two cores.
set -euo pipefail
out=${1:-bench_results}
shift || true
bench="$(dirname "$0")/../../build/bin/shadow_bench"
sponza="$(dirname "$0")/../../../shared/content/sponza/sponza.gltf"
mkdir -p "$out"
run() { local name=$1; shift; echo "== $name"; "$bench" "$@" --json "$out/$name.json"; }

run sm_contact --scene contact --mode sm --reference "$@"
for sc in atrium contact; do
  run cascades_$sc --scene $sc --mode cascades --reference "$@"
  for m in off edge depth-extent; do run cascades_${sc}_$m --scene $sc --mode cascades --masking $m "$@"; done
done
for sc in contact atrium foliage "$sponza"; do
  n=$(basename "$sc" .gltf)
  for v in 0 1; do for spp in 1 32; do
    run izb_${n}_v${v}_spp$spp --scene "$sc" --view $v --spp $spp --size 512x512 --izb 512 \
      --mode izb,izb+csm --csm-test hertel,bary --frames 2 --warmup 1 --reference "$@"
  done; done
done
# Coverage tests compared on the same caster set: every mesh forced into the CSM (no automatic skip).
for sc in contact atrium foliage "$sponza"; do
  n=$(basename "$sc" .gltf)
  for v in 0 1; do
    run culling_${n}_v$v --scene "$sc" --view $v --size 512x512 --izb 512 --mode izb+csm --csm-test hertel,bary \
      --csm-choice on --frames 2 --warmup 1 --reference "$@"
  done
done
for sc in atrium "$sponza"; do
  n=$(basename "$sc" .gltf)
  for v in 0 1; do
    run pays_${n}_v$v --scene "$sc" --view $v --size 1920x1080 --izb 1024 --mode izb,izb+csm --csm-test bary \
      --frames 3 --warmup 1 "$@"
  done
done
for c in auto off on; do
  run foliage_choice_$c --scene foliage --size 1920x1080 --izb 1024 --mode izb+csm --csm-choice $c --frames 3 --warmup 1 "$@"
done
# Alpha-tested casters (the canopy's leaf cards) in every technique against the alpha-aware reference.
for size in 256 512; do for v in 0 1; do
  run canopy_v${v}_${size}_spp1 --scene canopy --view $v --size ${size}x$size --izb 512 \
    --mode sm,cascades,izb,izb+csm --frames 5 --warmup 2 --reference "$@"
  run canopy_v${v}_${size}_spp32 --scene canopy --view $v --size ${size}x$size --izb 512 --spp 32 \
    --mode izb --frames 3 --warmup 1 --reference "$@"
done; done
