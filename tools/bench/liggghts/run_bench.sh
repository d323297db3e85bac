#!/usr/bin/env bash
# LIGGGHTS peer benchmark for pdamp: vertically shaken closed cylinder (Mao et al. 2004, Table 2 bed).
# Reruns everything (contact-law checks, settle + shake for two wall variants and three sizes)
# and prints the throughputs of the measured (shaking) phase.
# env overrides: DT=2.5e-6 (time step, s)  SIZES="1246:10e-3 4984:20e-3 19936:40e-3"  NSETTLE=50000
#                NWARM (default: one shaking period)  NMEAS (default: three periods)
#                VARIANTS="frame mesh" (default: frame)  VALIDATE=1  LIGGGHTS=liggghts
set -euo pipefail
cd "$(dirname "$0")"
LIGGGHTS=${LIGGGHTS:-liggghts}
SIZES=${SIZES:-"1246:10e-3 4984:20e-3 19936:40e-3"}   # N : cylinder diameter D (D scaled by sqrt(N/1246))
DT=${DT:-2.5e-6}
NSETTLE=${NSETTLE:-50000}     # settling (not measured)
NWARM=${NWARM:-$(awk -v dt="$DT" 'BEGIN { printf "%d", 1 / (30.8 * dt) + 0.5 }')}   # 1 shaking period at 30.8 Hz (not measured)
NMEAS=${NMEAS:-$((3 * NWARM))}  # 3 shaking periods, measured
VARIANTS=${VARIANTS:-"frame"}
VALIDATE=${VALIDATE:-1}
H=24.64e-3
mkdir -p runs runs/validate
command -v "$LIGGGHTS" >/dev/null || { echo "need LIGGGHTS: apt-get install -y liggghts" >&2; exit 1; }
("$LIGGGHTS" -h </dev/null 2>&1 || true) | grep -m1 "LIGGGHTS (Version" || true
echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-), nproc=$(nproc), $(date -u +%FT%TZ)"
# NB: liggghts must be started from this directory (relative includes) and with a
# real -screen file (-screen none segfaults in fix insert/pack of 3.8.0).

if [ "$VALIDATE" = 1 ]; then
  echo "== contact-law checks (static overlap, restitution)"
  "$LIGGGHTS" -var dt "$DT" -var D 10e-3 -in in.validate_static -log runs/validate/static.log -screen runs/validate/static.screen
  grep "^RESULT" runs/validate/static.log
  for v0 in 0.01 0.1 0.3 1.0 2.0; do
    "$LIGGGHTS" -var dt "$DT" -var v0 $v0 -var D 10e-3 -in in.validate_restitution -log runs/validate/rest_$v0.log -screen runs/validate/rest_$v0.screen
    grep "^RESULT" runs/validate/rest_$v0.log
  done
  echo "   (e_pp is for relative speed 2*v0; compare with restitution_ref.py, column LIGGGHTS-law VV)"
  python3 restitution_ref.py > runs/validate/restitution_ref.txt
fi

RES=runs/results.tsv
printf "variant\tN\tD_m\tsteps\twall_s\tparticle_steps_per_s\tmean_pp_contacts\tneigh_pairs_end\tneigh_builds\tproc_cpu_util\tloadavg_before\n" > "$RES"
for s in $SIZES; do
  N=${s%%:*}; D=${s##*:}; tag=n$N
  echo "== N=$N D=$D: settling $NSETTLE steps"
  /usr/bin/time -f "%e %U %S" -o runs/settle_$tag.time \
    "$LIGGGHTS" -var dt "$DT" -var N "$N" -var D "$D" -var tag "$tag" -var nsettle "$NSETTLE" \
      -in in.settle -log runs/settle_$tag.log -screen runs/settle_$tag.screen
  echo "   settle wall $(cut -d' ' -f1 runs/settle_$tag.time) s"
  for v in $VARIANTS; do
    la=$(cut -d' ' -f1 /proc/loadavg)
    extra=()
    if [ "$v" = mesh ]; then
      stl=cyl_D$D.stl
      python3 gen_stl.py "$D" "$H" "$stl" >/dev/null
      extra=(-var stl "$stl")
    fi
    echo "== N=$N variant=$v: warmup $NWARM + measured $NMEAS steps (loadavg $la)"
    /usr/bin/time -f "%e %U %S" -o runs/${v}_$tag.time \
      "$LIGGGHTS" -var dt "$DT" -var D "$D" -var tag "$tag" "${extra[@]}" -var nwarm "$NWARM" -var nmeas "$NMEAS" \
        -in in.shake_$v -log runs/${v}_$tag.log -screen runs/${v}_$tag.screen
    # whole-process CPU share (user+sys)/elapsed: < ~0.97 means the run was slowed by other load
    util=$(awk '{printf "%.3f", ($2+$3)/$1}' runs/${v}_$tag.time)
    read -r n st wall thr con nei bld < <(python3 parse_log.py runs/${v}_$tag.log)
    printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n" "$v" "$n" "$D" "$st" "$wall" "$thr" "$con" "$nei" "$bld" "$util" "$la" >> "$RES"
    echo "   $v N=$n steps=$st wall=${wall}s throughput=${thr} particle-steps/s mean_contacts=$con cpu_util=$util"
  done
done
echo
column -t -s$'\t' "$RES" 2>/dev/null || cat "$RES"
