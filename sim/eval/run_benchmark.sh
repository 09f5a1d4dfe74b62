#!/usr/bin/env bash
# The full evaluation of docs/EVALUATION.md, in one command: scenarios 1-6, the 50-trial random
# benchmark (scenario 7), crowd densities 5/10/15/20, walking speeds 0.75/1.2/1.7 m/s, three
# interaction-space sizes, the constrained worlds (obstacles beside the walk 1.2/1.0/0.8 m from
# it, and dead-end corridors) and both recorded-pedestrian files, for every method; then the plots
# and one report (OUT/REPORT.md: every table, the wall time, trials per minute).
#
#   sim/eval/run_benchmark.sh [OUT]          (default: eval-full; ~2 h 20 min on 2 cores)
#
# Environment: EVAL (the companion-eval binary, default build/release/sim/companion-eval),
# TRIALS (random trials of scenario 7, default 50), VARIANT_TRIALS (per crowd/speed/size/clutter/dead-end case,
# default 10), METHODS (default objective,fixed_behind,fixed_side,pid; add policy with a policy
# file in CONFIG), CONFIG (a daemon configuration for every trial, default: built-in defaults),
# WALKERS (recorded files: accompany each of the N people who walk farthest, default 10),
# DURATION_S (cut every trial to this long: CI's reduced run), JOBS (trials in parallel), STEPS
# (default "paper variants recorded"; variants = "crowds speeds sizes constrained": run a subset,
# e.g. one per sitting of a run longer than a working session; the report takes every step's
# latest results found in OUT).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-eval-full}
eval_bin=${EVAL:-build/release/sim/companion-eval}
trials=${TRIALS:-50}
variant_trials=${VARIANT_TRIALS:-10}
walkers=${WALKERS:-10}
methods=${METHODS:-objective,fixed_behind,fixed_side,pid}
extra=()
if [[ -n "${CONFIG:-}" ]]; then extra+=(-c "$CONFIG"); fi
if [[ -n "${DURATION_S:-}" ]]; then extra+=(--duration-s "$DURATION_S"); fi
if [[ -n "${JOBS:-}" ]]; then extra+=(--jobs "$JOBS"); fi
if [[ ! -x "$eval_bin" ]]; then
  echo "run_benchmark: $eval_bin not found (make build, or set EVAL)" >&2
  exit 2
fi
steps=${STEPS:-paper variants recorded}
steps=${steps//variants/crowds speeds sizes constrained}
dirs=(paper crowds speeds sizes constrained recorded-biwi_hotel recorded-crowds_zara01)
known="paper crowds speeds sizes constrained recorded"
for step in $steps; do  # checked before anything runs: a typo must not cost an hour's run first
  if [[ " $known " != *" $step "* ]]; then
    echo "run_benchmark: unknown step '$step' (variants or one of: $known)" >&2
    exit 2
  fi
done
mkdir -p "$out"
run() {  # one companion-eval run into $out/$1, its console output kept in $out/$1.log
  local name=$1
  shift
  "$eval_bin" "${extra[@]}" --method "$methods" --out "$out/$name" "$@" >"$out/$name.log"
  tail -n 1 "$out/$name.log"
}
for step in $steps; do
  case $step in
    paper) run paper --case paper --trials "$trials" --samples ;;
    crowds | speeds | sizes | constrained) run "$step" --case "$step" --trials "$variant_trials" ;;
    recorded)
      for f in biwi_hotel crowds_zara01; do
        run "recorded-$f" --pedestrians "sim/data/pedestrians/$f.txt" --frame-period 0.4 \
          --walkers "$walkers" --samples
      done
      ;;
  esac
done
for d in "${dirs[@]}"; do
  if [[ -d "$out/$d" ]]; then /usr/bin/python3 sim/eval/plot_eval.py "$out/$d" >/dev/null; fi
done

# Totals from the runs' own summaries ("N trials in S s"): steps may have run separately.
summaries=()
for d in "${dirs[@]}"; do
  if [[ -f "$out/$d/summary.md" ]]; then summaries+=("$out/$d/summary.md"); fi
done
read -r total seconds < <(cat "${summaries[@]}" /dev/null | awk '/ trials in [0-9]+ s / {
  n += $1; s += $4 } END { print n + 0, s + 0 }')
{
  echo "# companion-eval: the full benchmark"
  echo
  echo "Command: \`sim/eval/run_benchmark.sh $out\` (TRIALS=$trials, VARIANT_TRIALS=$variant_trials,"
  echo "WALKERS=$walkers,"
  echo "METHODS=$methods${CONFIG:+, CONFIG=$CONFIG}${DURATION_S:+, DURATION_S=$DURATION_S}${STEPS:+; the last sitting STEPS=$STEPS, the report gathers every step found in OUT}), $(date -u +%Y-%m-%d)," \
    "commit $(git rev-parse --short HEAD 2>/dev/null || echo '?')."
  echo
  echo "$total trials in $seconds s of wall time on $(nproc) cores:" \
    "$(awk -v n="$total" -v s="$seconds" 'BEGIN { printf "%.1f", (s > 0 ? 60 * n / s : 0) }') trials/min."
  for d in "${dirs[@]}"; do
    [[ -f "$out/$d/summary.md" ]] || continue
    echo
    echo "# $d"
    tail -n +2 "$out/$d/summary.md"
  done
} >"$out/REPORT.md"
echo "run_benchmark: $out/REPORT.md ($total trials, $seconds s)"
