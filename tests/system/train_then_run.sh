#!/usr/bin/env bash
# The learned selector's whole path: companion-train writes a policy file (a few hundred
# decisions: the pipeline, not a useful policy), companiond's configuration names it, and
# companion-eval's closed loop runs the daemon with it (the file loads, the policy task chooses).
# Usage: train_then_run.sh COMPANION_TRAIN COMPANION_EVAL CONFIG_YAML
set -euo pipefail
train=$1 eval=$2 config=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$train" --out "$work/p.bin" --steps 256 --envs 2 --eval-every 4 --eval-episodes 1 --log "$work/t.csv" > "$work/train.log"
test -s "$work/p.bin"
grep -q '^8,256,' "$work/t.csv"
# The warm start alone (--steps 0): behaviour cloning, one DAgger round, the imitated policy
# evaluated and written as the file.
"$train" --out "$work/w.bin" --steps 0 --envs 2 --imitate-rollouts 1 --dagger-rounds 1 --eval-episodes 1 > "$work/warm.log"
grep -q 'imitation round 1 (DAgger): 64 samples' "$work/warm.log"
grep -q "wrote $work/w.bin (update 0" "$work/warm.log"
test -s "$work/w.bin"
if "$train" --out "$work/x.bin" --steps 0 --dagger-rounds 1 > "$work/x.log" 2>&1; then
  echo "companion-train accepted DAgger rounds without imitation rollouts"; exit 1
fi
grep -q -- "--dagger-rounds needs --imitate-rollouts" "$work/x.log"
sed "s|^  file: \"\"|  file: \"$work/p.bin\"|" "$config" > "$work/policy.yaml"
grep -q "file: \"$work/p.bin\"" "$work/policy.yaml"
"$eval" --case open --method policy --duration-s 6 --jobs 1 -c "$work/policy.yaml" --out "$work/eval" > "$work/eval.log"
# The trial ran with the file (that the daemon then chooses by the policy is
# ClosedLoop.APolicyFileInTheConfigurationChoosesThePoint); a truncated file is refused.
grep -q '^| policy |' "$work/eval/summary.md"
head -c 100 "$work/p.bin" > "$work/broken.bin"
sed "s|$work/p.bin|$work/broken.bin|" "$work/policy.yaml" > "$work/broken.yaml"
if "$eval" --case open --method policy --duration-s 1 -c "$work/broken.yaml" --out "$work/e2" > "$work/e2.log" 2>&1; then
  echo "companion-eval accepted a truncated policy file"; exit 1
fi
grep -q "policy.file" "$work/e2.log"
echo "train -> policy file -> closed loop: ok"
