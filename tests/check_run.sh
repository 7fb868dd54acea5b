#!/usr/bin/env bash
# check_run.sh [--fresh PATH]... [--windowed] [--png "FILE [png_check options]"]... -- COMMAND... [--then COMMAND...]...
# Runs each COMMAND in turn with the validation layer on and passes only when every one exits 0 and
# prints no validation message ("[vulkan]"), no "validation requested but" warning and, with
# --windowed, no sign of having fallen back to headless; then runs png_check (PNG_CHECK, else beside
# this script's build) on each --png. --fresh paths are removed first, so frames of an earlier run
# cannot pass for this one's. CTest's PASS_REGULAR_EXPRESSION would ignore the exit code; this does not.
set -uo pipefail
fresh=() pngs=() windowed=0
while (($#)); do
  case $1 in
    --fresh) fresh+=("$2"); shift 2 ;;
    --png) pngs+=("$2"); shift 2 ;;
    --windowed) windowed=1; shift ;;
    --) shift; break ;;
    *) echo "check_run: unknown option $1" >&2; exit 2 ;;
  esac
done
(($#)) || { echo "check_run: no command" >&2; exit 2; }
: "${PNG_CHECK:?check_run: set PNG_CHECK to the png_check executable}"
export ENGINE_VALIDATION=1
for p in "${fresh[@]}"; do rm -rf -- "$p"; done

fail_pattern='\[vulkan\]|validation requested but'
((windowed)) && fail_pattern+='|running headless|no display found'
run() {
  local log rc
  log=$(mktemp)
  echo "check_run: $*"
  "$@" >"$log" 2>&1
  rc=$?
  cat "$log"
  if ((rc != 0)); then echo "check_run: FAILED: exit code $rc: $1"; rm -f "$log"; return 1; fi
  if grep -Eq "$fail_pattern" "$log"; then
    echo "check_run: FAILED: output matches '$fail_pattern': $(grep -Em1 "$fail_pattern" "$log")"
    rm -f "$log"
    return 1
  fi
  rm -f "$log"
}

cmd=()
status=0
for a in "$@" --then; do
  if [[ $a == --then ]]; then
    ((${#cmd[@]})) && { run "${cmd[@]}" || status=1; }
    cmd=()
  else
    cmd+=("$a")
  fi
done
((status == 0)) || exit 1
for spec in "${pngs[@]}"; do
  # shellcheck disable=SC2086  # the spec is a file and options, split on spaces
  "$PNG_CHECK" $spec || { echo "check_run: FAILED: png_check $spec"; status=1; }
done
exit $status
