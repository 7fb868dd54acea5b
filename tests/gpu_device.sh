#!/usr/bin/env bash
# gpu_device.sh [GPU_TESTS] [OUT_DIR] [MODES] [SHARDS]: the whole GPU test suite on the machine's GPU
# (ENGINE_DEVICE=gpu, default build/bin/gpu_tests), once with the validation layer and once with its
# synchronization checks too; any validation message fails a test. Writes each run's log and GoogleTest
# JSON under OUT_DIR (default gpu_device_out) and prints a summary: tests run, passed, skipped (with the
# reason each gave) and failed. MODES (default "validation syncval") picks the runs. SHARDS (default 1)
# splits each run into that many GoogleTest shards (GTEST_TOTAL_SHARDS), and every shard of every mode
# runs side by side: the validation layers spend CPU time, which a many-core machine's cores share, so
# the suite takes a fraction of its serial time (on a 16-core H200 host, 4 shards: both modes in under
# 5 minutes; one mode alone took over 10 serially). Exits non-zero when a run failed.
set -uo pipefail
tests=${1:-build/bin/gpu_tests}
out=${2:-gpu_device_out}
modes=${3:-validation syncval}
mkdir -p "$out"
export ENGINE_DEVICE=${ENGINE_DEVICE:-gpu}
status=0

summary() {  # LOG: counts and skip reasons from GoogleTest's output
  awk '
    /^\[ RUN      \]/ { run++; reason = ""; in_skip = 0; next }
    /: Skipped$/ { in_skip = 1; next }
    /^\[       OK \]/ { passed++; next }
    /^\[  SKIPPED \] [A-Za-z].* ms\)$/ { skipped++; reasons[reason]++; in_skip = 0; next }
    /^\[  FAILED  \] [A-Za-z].* ms\)$/ { failed++; sub(/,$/, "", $4); names = names "\n    " $4; next }
    in_skip { reason = reason (reason == "" ? "" : " ") $0 }
    END {
      printf "  run %d, passed %d, skipped %d, failed %d\n", run, passed, skipped, failed
      for (r in reasons) printf "    skipped %d: %s\n", reasons[r], r
      if (failed) printf "  failed:%s\n", names
    }' "$1"
}

shards=${4:-1}
mode_env() {  # MODE: the variable that turns the mode's validation on
  if [[ $1 == syncval ]]; then echo ENGINE_SYNC_VALIDATION=1; else echo ENGINE_VALIDATION=1; fi
}
# One shard of one mode: its log, JSON and exit code under $out.
run_shard() {  # MODE INDEX
  local mode=$1 index=$2
  env "$(mode_env "$mode")" GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$index" "$tests" \
    --gtest_output=json:"$out/gpu_tests_${mode}_$index.json" >"$out/gpu_tests_${mode}_$index.log" 2>&1
  echo $? >"$out/gpu_tests_${mode}_$index.rc"
}
start=$SECONDS
for mode in $modes; do
  rm -f "$out"/gpu_tests_"${mode}"_*  # an earlier run's shards (perhaps more of them) would be summed in
  for ((i = 0; i < shards; ++i)); do run_shard "$mode" "$i" & done
done
wait
for mode in $modes; do
  log=$out/gpu_tests_$mode.log
  cat "$out"/gpu_tests_"${mode}"_*.log >"$log"
  rc=0
  for f in "$out"/gpu_tests_"${mode}"_*.rc; do ((rc |= $(cat "$f"))); done
  echo "gpu_tests, ENGINE_DEVICE=$ENGINE_DEVICE, $(mode_env "$mode"), $shards shard(s) side by side: exit $rc, all runs done in $((SECONDS - start)) s"
  summary "$log" | tee "$out/summary_$mode.txt"
  # The synchronization canary (RobustnessTest.SyncValidationReportsAMissingBarrier) provokes one
  # hazard on a buffer named "hazard target" and passes only when it is reported: not counted here.
  echo "  validation messages: $(grep '^\[vulkan\]' "$log" | grep -vc 'name = hazard target') (besides the canary's deliberate hazard)"
  ((rc == 0)) || status=1
done
exit $status
