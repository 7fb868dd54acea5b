#!/usr/bin/env bash
# The world-scale matrix with the benchmark: one scene at scale {0.01, 1, 100, 1000} x offset
# {0, 1e3, 1e4} (x and z), and at scale 100 1e5 and 1e6 units out through the large-world API
# (--large-world: Scene::origin), every technique (rt where the device has ray tracing) against Embree
# at 1 spp, and izb+csm and rt at 32 spp. Writes OUT/*.json (one per placement and spp) and
# OUT/matrix.md (one row per placement and technique). MODES1 and MODES32 override the mode lists
# (a device without ray tracing: MODES1=izb,izb+csm,sm,cascades,hybrid MODES32=izb+csm).
# usage: tests/bench/world_scale_matrix.sh BENCH SCENE VIEW WxH IZB OUT [shadow_bench options...]
# e.g.   tests/bench/world_scale_matrix.sh build/bin/shadow_bench ../shared/content/sponza/sponza.gltf 1 1920x1080 1024 out
set -uo pipefail
[[ $# -ge 6 ]] || { sed -n 2,9p "$0"; exit 2; }
bench=$1 scene=$2 view=$3 size=$4 izb=$5 out=$6
shift 6
extra=("$@")
mkdir -p "$out"
modes1=${MODES1:-izb,izb+csm,sm,cascades,hybrid,rt}
modes32=${MODES32:-izb+csm,rt}
status=0
run() {  # run SCALE OFFSET LARGE_WORLD
  local scale=$1 offset=$2 lw=$3 tag="s${1}_o${2}${3:+_lw}"
  for spp in 1 32; do
    local modes=$modes1
    [[ $spp == 32 ]] && modes=$modes32
    "$bench" --scene "$scene" --view "$view" --size "$size" --izb "$izb" --spp $spp --mode "$modes" --reference \
      --frames 2 --warmup 1 --scale "$scale" --offset "$offset,0,$offset" ${lw:+--large-world} \
      --json "$out/${tag}_spp$spp.json" "${extra[@]}" >"$out/${tag}_spp$spp.log" 2>&1 || status=1
  done
}
for scale in 1 0.01 100 1000; do
  for offset in 0 1000 10000; do run $scale $offset ""; done
done
run 100 100000 1
run 100 1000000 1
# The table: placement, spp, mode, mismatch rate, false shadowed, false lit, coverage MAE.
{
  echo "| scale | offset | spp | mode | mismatch | false shadowed | false lit | coverage MAE |"
  echo "|---|---|---|---|---|---|---|---|"
  for f in "$out"/*.json; do
    base=$(basename "$f" .json)
    python3 - "$f" "$base" <<'PY'
import json, sys
runs = json.load(open(sys.argv[1]))
tag = sys.argv[2]
scale = tag.split("_")[0][1:]
offset = tag.split("_")[1][1:] + (" (large world)" if "_lw" in tag else "")
for r in runs:
    if r.get("status") != "ran" or "reference" not in r: continue
    c = r["reference"]
    print(f"| {scale} | {offset} | {r['spp']} | {r['mode']} | {c['mismatch_rate']:.6f} | {c['false_shadowed']} | {c['false_lit']} | {c['coverage_mae']:.6f} |")
PY
  done
} >"$out/matrix.md"
echo "world_scale_matrix: $out/matrix.md"
exit $status
