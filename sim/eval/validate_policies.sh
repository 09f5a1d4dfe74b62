#!/usr/bin/env bash
# Choose a learned policy by what the benchmark counts: every candidate policy file (e.g. the
# checkpoints of `companion-train --checkpoints DIR`) drives the closed loop (companion-eval,
# the daemon, MPPI-CBF, the simulated devices) through the random validation worlds, never the
# benchmark's seeds 1-50; the objective selector runs the same worlds as the baseline. The table
# goes to OUT/VALIDATION.md, the chosen file is copied to OUT/best.bin.
#
#   sim/eval/validate_policies.sh OUT POLICY.bin [POLICY.bin ...]
#
# Chosen: the most successes; among equals, the smallest e_x + e_y (the mean of the trials'
# RMSEs), then the first named. Environment: EVAL (companion-eval, default
# build/release/sim/companion-eval), SEED (the first validation seed, default 101), TRIALS
# (default 80: seeds 101-180), CONFIG (the daemon configuration of every trial, default
# config/companiond.yaml; the candidate goes in by --policy-file), DURATION_S, JOBS (as
# companion-eval's options).
set -euo pipefail
cd "$(dirname "$0")/../.."
if [[ $# -lt 2 ]]; then
  echo "usage: sim/eval/validate_policies.sh OUT POLICY.bin [POLICY.bin ...]" >&2
  exit 2
fi
out=$1
shift
eval_bin=${EVAL:-build/release/sim/companion-eval}
seed=${SEED:-101}
trials=${TRIALS:-80}
config=${CONFIG:-config/companiond.yaml}
extra=(--case random --seed "$seed" --trials "$trials")
if [[ -n "${DURATION_S:-}" ]]; then extra+=(--duration-s "$DURATION_S"); fi
if [[ -n "${JOBS:-}" ]]; then extra+=(--jobs "$JOBS"); fi
if [[ ! -x "$eval_bin" ]]; then
  echo "validate_policies: $eval_bin not found (make build, or set EVAL)" >&2
  exit 2
fi
names=()
for p in "$@"; do  # all checked before the first (long) run
  if [[ ! -s "$p" ]]; then
    echo "validate_policies: $p: no such policy file" >&2
    exit 2
  fi
  name=$(basename "$p" .bin)
  if [[ $name == *[[:space:]\|]* ]]; then  # it names a table cell the choice reads back
    echo "validate_policies: '$p': a candidate's name may not hold spaces or '|'" >&2
    exit 2
  fi
  if [[ " ${names[*]} " == *" $name "* || $name == objective ]]; then
    echo "validate_policies: two candidates named '$name' (their results would share a directory)" >&2
    exit 2
  fi
  names+=("$name")
done
mkdir -p "$out"

# Successes, failures (seed: what) and mean RMSEs of one run's trials.csv, as one table row.
row() {
  awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
    { n++; ok += $col["success"]; ex += $col["rmse_ex_m"]; ey += $col["rmse_ey_m"]
      et += $col["rmse_etheta_rad"]
      if (!$col["success"]) { f = $col["failure"]; sub(/ at t=.*/, "", f)
        fails = fails (fails ? "; " : "") $col["seed"] ": " f } }
    END { if (n == 0) exit 1
      printf "| %s | %d / %d | %.3f | %.3f | %.3f | %.3f | %s |\n", name, ok, n, ex / n, ey / n,
        et / n, (ex + ey) / n, (fails ? fails : "-") }' "$2"
}

"$eval_bin" "${extra[@]}" -c "$config" --method objective --out "$out/objective" >"$out/objective.log"
rows=("$(row objective "$out/objective/trials.csv")")
for p in "$@"; do
  name=$(basename "$p" .bin)
  "$eval_bin" "${extra[@]}" -c "$config" --policy-file "$p" --method policy --out "$out/$name" \
    >"$out/$name.log"
  rows+=("$(row "$name" "$out/$name/trials.csv")")
  echo "${rows[-1]}"
done

# Best candidate: most successes (column 3 "k / n"), then the smallest e_x + e_y (column 7),
# then the first named.
best=$(printf '%s\n' "${rows[@]:1}" | awk -F'|' '{ split($3, s, "/"); print s[1] + 0, $7 + 0, $2 }' |
  sort -s -k1,1nr -k2,2g | head -n 1 | awk '{ print $3 }')
for p in "$@"; do
  if [[ $(basename "$p" .bin) == "$best" ]]; then cp "$p" "$out/best.bin"; fi
done
{
  echo "# Policy validation: the closed loop on random seeds $seed-$((seed + trials - 1))"
  echo
  echo "Command: \`SEED=$seed TRIALS=$trials${DURATION_S:+ DURATION_S=$DURATION_S}" \
    "sim/eval/validate_policies.sh $out $*\`, $(date -u +%Y-%m-%d)."
  echo
  echo "| selector | successes | e_x (m) | e_y (m) | e_θ (rad) | e_x + e_y | failures (seed: what) |"
  echo "|---|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "Chosen: **$best** (copied to $out/best.bin): the most successes, then the smallest e_x + e_y."
} >"$out/VALIDATION.md"
echo "validate_policies: chose $best ($out/VALIDATION.md, $out/best.bin)"
