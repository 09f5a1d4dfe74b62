#!/usr/bin/env bash
# The learned selector's whole path: companion-train writes a policy file (a few hundred
# decisions: the pipeline, not a useful policy), companiond's configuration names it, and
# companion-eval's closed loop runs the daemon with it (the file loads, the policy task chooses).
# With --checkpoints every candidate is kept, and validate_policies.sh runs them through
# companion-eval's closed loop and keeps the best.
# Usage: train_then_run.sh COMPANION_TRAIN COMPANION_EVAL CONFIG_YAML VALIDATE_POLICIES_SH
set -euo pipefail
train=$1 eval=$2 config=$3 validate=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$train" --out "$work/p.bin" --steps 256 --envs 2 --eval-every 4 --eval-episodes 1 --log "$work/t.csv" > "$work/train.log"
test -s "$work/p.bin"
grep -q '^8,256,' "$work/t.csv"
# The warm start (behaviour cloning, one DAgger round; the imitated policy evaluated and written
# as the file) and PPO to 256 steps (the imitation's 64 among them: updates 2, 4, 6), every
# candidate kept (--checkpoints).
"$train" --out "$work/w.bin" --steps 256 --envs 2 --imitate-rollouts 1 --dagger-rounds 1 --eval-every 2 --eval-episodes 1 --checkpoints "$work/ck" > "$work/warm.log"
grep -q 'imitation round 1 (DAgger): 64 samples' "$work/warm.log"
grep -q "wrote $work/w.bin (update 0" "$work/warm.log"
test -s "$work/w.bin"
for c in imitation-0 imitation-1 update-00002 update-00004 update-00006; do test -s "$work/ck/$c.bin"; done
if cmp -s "$work/ck/imitation-0.bin" "$work/ck/imitation-1.bin"; then
  echo "the DAgger round's checkpoint is the behaviour cloning's"; exit 1
fi
env EVAL="$eval" TRIALS=1 DURATION_S=3 JOBS=1 CONFIG="$config" bash "$validate" "$work/val" "$work/ck/imitation-1.bin" "$work/ck/update-00006.bin" > "$work/val.log"
grep -q '^| objective | 1 / 1 |' "$work/val/VALIDATION.md"
grep -q '^| imitation-1 | 1 / 1 |' "$work/val/VALIDATION.md"
grep -q '^| update-00006 | 1 / 1 |' "$work/val/VALIDATION.md"
test -s "$work/val/best.bin"
# --policy-file, the way validate_policies.sh hands each candidate in, refuses a truncated file.
head -c 100 "$work/ck/update-00006.bin" > "$work/cut.bin"
if "$eval" --case open --method policy --duration-s 1 --policy-file "$work/cut.bin" --out "$work/e3" > "$work/e3.log" 2>&1; then
  echo "companion-eval accepted a truncated --policy-file"; exit 1
fi
grep -q "policy.file $work/cut.bin" "$work/e3.log"
if "$train" --out "$work/x.bin" --steps 0 --dagger-rounds 1 > "$work/x.log" 2>&1; then
  echo "companion-train accepted DAgger rounds without imitation rollouts"; exit 1
fi
grep -q -- "--dagger-rounds needs --imitate-rollouts" "$work/x.log"
if "$train" --out "$work/y.bin" --steps 0 --checkpoints "$work/p.bin/ck" > "$work/y.log" 2>&1; then
  echo "companion-train accepted a checkpoint directory it cannot make"; exit 1
fi
grep -q -- "--checkpoints $work/p.bin/ck: cannot make the directory" "$work/y.log"
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
