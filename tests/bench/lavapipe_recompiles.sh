#!/bin/bash
# Finds passes that lavapipe compiles anew at every dispatch (BENCHMARKS.md, "Shaders compiled at every
# dispatch on lavapipe"). Mesa 22.x folds the uniform-buffer values on which an `if` or a loop's bound
# alone depends into the shader at each dispatch and compiles the result, keeping no variant; its
# shader cache then hides most of the cost (1-2 ms a dispatch instead of 50-400). So each case runs
# twice, with the cache and without (MESA_SHADER_CACHE_DISABLE), and a pass whose time grows by more
# than THRESHOLD ms without it is listed. Exits 1 when any is.
#
#   tests/bench/lavapipe_recompiles.sh [BENCH] [THRESHOLD]    (defaults: build/bin/shadow_bench, 30)
#
# About fifteen minutes on a 2-core machine. Each pass's time varies by a few ms between runs, and a
# compile costs tens of ms at least, hence the threshold.
set -u
bench=${1:-build/bin/shadow_bench}
threshold=${2:-30}
sponza=${SPONZA:-../shared/content/sponza/sponza.gltf}
modes=sm,cascades,izb,izb+csm,hybrid,hybrid+csm
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
found=0

check() {  # label, then shadow_bench's arguments
  local label=$1
  shift
  for cache_off in false true; do
    if ! MESA_SHADER_CACHE_DISABLE=$cache_off "$bench" "$@" --device lavapipe --step-times --frames 4 --warmup 2 \
      > "$out/$label.$cache_off" 2>&1; then
      echo "$label: shadow_bench failed: $(tail -1 "$out/$label.$cache_off")"
      found=1
      return
    fi
  done
  python3 - "$out/$label.false" "$out/$label.true" "$label" "$threshold" <<'PY' || found=1
import re, sys
def passes(path):
    times, mode = {}, None
    for line in open(path):
        if re.match(r'^[a-z+]+ ', line):
            mode = line.split()[0]
        m = re.match(r'^    ([a-z_0-9]+(?: [0-9]+)?) +([0-9.]+) ms$', line)
        if m and mode and not m.group(1).startswith(('frame', 'light ', 'shadows')):
            times[(mode, m.group(1))] = float(m.group(2))
    return times
cached, uncached = passes(sys.argv[1]), passes(sys.argv[2])
label, threshold = sys.argv[3], float(sys.argv[4])
grown = [(k, cached[k], uncached[k]) for k in cached if k in uncached and uncached[k] - cached[k] > threshold]
for (mode, name), a, b in grown:
    print(f"{label}: {mode} {name}: {a:.1f} ms with the shader cache, {b:.1f} without")
sys.exit(1 if grown else 0)
PY
}

check contact --scene contact --view 0 --size 640x360 --izb 512 --mode $modes
check contact-32spp --scene contact --view 0 --size 320x180 --izb 512 --spp 32 --mode izb,izb+csm,hybrid
check contact-hard --scene contact --view 1 --size 640x360 --izb 512 --light-size 0 --mode $modes
check courtyard --scene content/levels/courtyard.json --view 0 --size 640x360 --izb 512 --detail low --mode sm,izb,hybrid
check courtyard-lamp --scene content/levels/courtyard.json --view 0 --size 640x360 --izb 512 --detail low --light spot --mode sm,cascades,izb
check lamps-point --scene lamps --view 0 --light point --size 640x360 --izb 512 --mode $modes
check lamps-point-radius --scene lamps --view 0 --light point --light-radius 0.1 --size 640x360 --izb 512 --mode sm,cascades,izb,hybrid
check lamps-spot --scene lamps --view 1 --light spot --size 640x360 --izb 512 --mode $modes
check lamps-every-light --scene lamps --view 1 --size 640x360 --izb 512 --mode sm,izb,hybrid
check atrium --scene atrium --view 0 --size 640x360 --izb 512 --mode $modes
check foliage --scene foliage --view 0 --size 640x360 --izb 512 --mode $modes
check canopy --scene canopy --view 0 --size 640x360 --izb 512 --mode $modes
if [ -f "$sponza" ]; then check sponza --scene "$sponza" --view 1 --size 640x360 --izb 512 --mode $modes; fi
[ $found = 0 ] && echo "no pass grew by more than $threshold ms without the shader cache"
exit $found
