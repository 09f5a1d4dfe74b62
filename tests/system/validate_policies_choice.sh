#!/usr/bin/env bash
# sim/eval/validate_policies.sh chooses the policy with the most closed-loop successes, then the
# smallest e_x + e_y, then the first named; it refuses missing and same-named candidates. The
# closed loop is a stand-in here (EVAL): its trials.csv is the candidate "policy file"'s own text,
# so each candidate's results are known. (The real companion-eval path: train_then_run.sh.)
# Usage: validate_policies_choice.sh VALIDATE_POLICIES_SH
set -euo pipefail
script=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat >"$work/eval" <<'STANDIN'
#!/usr/bin/env bash
while [[ $# -gt 0 ]]; do
  case $1 in
    --policy-file) policy=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --method) method=$2; shift 2 ;;
    *) shift ;;
  esac
done
mkdir -p "$out"
echo "case,method,seed,success,failure,rmse_ex_m,rmse_ey_m,rmse_etheta_rad" >"$out/trials.csv"
if [[ $method == objective ]]; then
  echo "random,objective,101,1,,0.1,0.1,0.1" >>"$out/trials.csv"
else
  cat "$policy" >>"$out/trials.csv"
fi
STANDIN
chmod +x "$work/eval"
mkdir -p "$work/c1" "$work/c2"
printf 'random,policy,101,1,,0.1,0.1,0.2\nrandom,policy,102,0,collision with the person at t=3.0 s,0.2,0.2,0.2\n' >"$work/c1/fails.bin"
printf 'random,policy,101,1,,0.3,0.3,0.1\nrandom,policy,102,1,,0.3,0.3,0.1\n' >"$work/c1/loose.bin"
printf 'random,policy,101,1,,0.1,0.2,0.1\nrandom,policy,102,1,,0.1,0.2,0.1\n' >"$work/c1/tight.bin"
cp "$work/c1/tight.bin" "$work/c2/same.bin"
env EVAL="$work/eval" TRIALS=2 bash "$script" "$work/v" "$work/c1/fails.bin" "$work/c1/loose.bin" \
  "$work/c1/tight.bin" "$work/c2/same.bin" >"$work/out.log"
md="$work/v/VALIDATION.md"
grep -q '^| objective | 1 / 1 | 0.100 | 0.100 | 0.100 | 0.200 | - |$' "$md"
grep -q '^| fails | 1 / 2 | 0.150 | 0.150 | 0.200 | 0.300 | 102: collision with the person |$' "$md"
grep -q '^| loose | 2 / 2 | 0.300 | 0.300 | 0.100 | 0.600 | - |$' "$md"
grep -q '^Chosen: \*\*tight\*\*' "$md"
grep -q "^Command: \`SEED=101 TRIALS=2 sim/eval/validate_policies.sh $work/v $work/c1/fails.bin " "$md"
grep -q 'validate_policies: chose tight' "$work/out.log"
cmp "$work/v/best.bin" "$work/c1/tight.bin"
# The most successes wins over smaller errors.
env EVAL="$work/eval" TRIALS=2 bash "$script" "$work/v2" "$work/c1/fails.bin" "$work/c1/loose.bin" >/dev/null
cmp "$work/v2/best.bin" "$work/c1/loose.bin"
# Refusals before any run: a missing file, two candidates with one name.
if env EVAL="$work/eval" bash "$script" "$work/v3" "$work/nothing.bin" >"$work/e1.log" 2>&1; then
  echo "validate_policies accepted a missing policy file"; exit 1
fi
grep -q 'nothing.bin: no such policy file' "$work/e1.log"
if env EVAL="$work/eval" bash "$script" "$work/v4" "$work/c1/tight.bin" "$work/c1/tight.bin" >"$work/e2.log" 2>&1; then
  echo "validate_policies accepted two candidates named alike"; exit 1
fi
grep -q "two candidates named 'tight'" "$work/e2.log"
cp "$work/c1/tight.bin" "$work/c1/a b.bin"
if env EVAL="$work/eval" bash "$script" "$work/v5" "$work/c1/a b.bin" >"$work/e3.log" 2>&1; then
  echo "validate_policies accepted a candidate named with a space"; exit 1
fi
grep -q "may not hold spaces or '|'" "$work/e3.log"
test ! -e "$work/v3" && test ! -e "$work/v4" && test ! -e "$work/v5"
echo "validate_policies: chooses by successes, then e_x + e_y; refuses bad candidates: ok"
