#!/usr/bin/env bash
# After a libFuzzer run: did it find anything? (`make fuzz` calls it after each fuzzer.)
#
#   toolchain/fuzz_findings.sh FUZZER ARTIFACT_DIR TIMEOUT_S
#
# Looks at the artifacts libFuzzer wrote into ARTIFACT_DIR (its -artifact_prefix):
#   crash-*, leak-*, oom-*  a finding: listed, exit 1;
#   timeout-*               run once more alone (FUZZER -timeout=TIMEOUT_S FILE, the run's own
#                           limit): an input that times out again is a finding (exit 1); one
#                           that now runs in time was the machine stalling, not the input (a
#                           shared VM can pause for seconds): reported,
#                           renamed stalled-* so the next fuzzer's check does not see it, exit 0.
#                           The second run's output is kept in rerun-NAME.log either way.
# Nothing found: exit 0, silent.
set -uo pipefail

if [[ $# -ne 3 || ! -x "$1" || ! -d "$2" || ! "$3" =~ ^[1-9][0-9]*$ ]]; then
  echo "usage: $0 FUZZER ARTIFACT_DIR TIMEOUT_S (an executable fuzzer, a directory, seconds)" >&2
  exit 2
fi
fuzzer=$1
dir=$2
timeout_s=$3
found=0
shopt -s nullglob
for f in "$dir"/crash-* "$dir"/leak-* "$dir"/oom-*; do
  echo "fuzz finding: $f"
  found=1
done
for f in "$dir"/timeout-*; do
  log="$dir/rerun-$(basename "$f").log"
  if "$fuzzer" -timeout="$timeout_s" "$f" > "$log" 2>&1; then
    echo "fuzz: $(basename "$f") ran in time when run again: the machine stalled, not the input"
    mv "$f" "$dir/stalled-$(basename "$f")"
  else
    echo "fuzz finding: $f times out again ($log)"
    found=1
  fi
done
exit "$found"
