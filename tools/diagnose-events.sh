#!/usr/bin/env bash
# Where a hard run's collisions come from, as tables in Markdown (docs/hard-engine.md,
# "Where dense beds spend their collisions"), from a run made with
#   pdamp run --model hard --diagnose-events ...
# For each kind of collision: how many; the time since each sphere involved last collided,
# in decades of the soft law's contact time t_c at that approach speed (% of the spheres'
# intervals); the share of collisions within t_c of an earlier one of a sphere involved;
# the approach speeds (% of the collisions). Then what the host's impulses cost: the
# host-dependent predictions made anew per impulse.
# Usage: tools/diagnose-events.sh STORE [RUN_ID]   (default: the store's last run)
set -euo pipefail
[ $# -ge 1 ] && [ $# -le 2 ] || { sed -n '/^# Usage:/s/^# //p' "$0" >&2; exit 2; }
store=$1
[ -f "$store" ] || { echo "tools/diagnose-events.sh: no store '$store'" >&2; exit 2; }
run=${2:-$(sqlite3 "$store" "select max(run_id) from runs")}
[[ $run =~ ^[0-9]+$ ]] || { echo "tools/diagnose-events.sh: RUN_ID '$run' is not a run number" >&2; exit 2; }
stat() { sqlite3 "$store" "select coalesce(sum(value), 0) from run_statistics where run_id = $run and name = '$1'"; }
if [ "$(sqlite3 "$store" "select count(*) from run_statistics where run_id = $run and name like 'diagnosis_%'")" = 0 ]; then
  echo "tools/diagnose-events.sh: run $run of '$store' has no diagnosis: run it with pdamp run --model hard --diagnose-events" >&2
  exit 2
fi
percent() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.1f", 100 * a / b; else printf "-" }'; }

intervals=(dt_same_instant dt_below_0.01tc dt_0.01_0.1tc dt_0.1_1tc dt_1_10tc dt_10_100tc dt_above_100tc dt_first)
speeds=(v_below_1e-4 v_1e-4_1e-3 v_1e-3_1e-2 v_1e-2_1e-1 v_1e-1_1 v_above_1)
kinds=(sphere_sphere side_wall cap rider)
total=0
for kind in "${kinds[@]}"; do
  for s in "${speeds[@]}"; do total=$((total + $(stat "diagnosis_${kind}_$s"))); done
done
echo "run $run: $total collisions with a law"
echo
echo "| kind | collisions | % of all | same instant | < 0.01 t_c | 0.01–0.1 | 0.1–1 | 1–10 | 10–100 | ≥ 100 t_c | first | within t_c |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for kind in "${kinds[@]}"; do
  n=0 spheres=0
  for s in "${speeds[@]}"; do n=$((n + $(stat "diagnosis_${kind}_$s"))); done
  for b in "${intervals[@]}"; do spheres=$((spheres + $(stat "diagnosis_${kind}_$b"))); done
  row="| $kind | $n | $(percent "$n" "$total")"
  for b in "${intervals[@]}"; do row+=" | $(percent "$(stat "diagnosis_${kind}_$b")" "$spheres")"; done
  echo "$row | $(percent "$(stat "diagnosis_${kind}_within_tc")" "$n") |"
done
echo
echo "| kind | < 10⁻⁴ m/s | 10⁻⁴–10⁻³ | 10⁻³–10⁻² | 10⁻²–10⁻¹ | 0.1–1 | ≥ 1 m/s |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for kind in "${kinds[@]}"; do
  n=0
  for s in "${speeds[@]}"; do n=$((n + $(stat "diagnosis_${kind}_$s"))); done
  row="| $kind"
  for s in "${speeds[@]}"; do row+=" | $(percent "$(stat "diagnosis_${kind}_$s")" "$n")"; done
  echo "$row |"
done
echo
impulses=$(stat host_impulses)
per_impulse() { awk -v a="$1" -v b="$impulses" 'BEGIN { if (b > 0) printf "%.2f", a / b; else printf "-" }'; }
tiers=$(($(stat near_repredictions) + $(stat imminent_repredictions) + $(stat close_repredictions)))
echo "| host impulses | touching re-predictions / impulse | touching deferrals / impulse | tier re-predictions / impulse | rests | knock-offs | jam merges (spheres) |"
echo "|---:|---:|---:|---:|---:|---:|---:|"
echo "| $impulses | $(per_impulse "$(stat touching_repredictions)") | $(per_impulse "$(stat touching_deferrals)") | $(per_impulse "$tiers") | $(stat bed_rests) | $(stat bed_knock_offs) | $(stat jam_merges) ($(stat jam_merged_spheres)) |"
