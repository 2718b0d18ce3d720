#!/usr/bin/env bash
# The fsei stability stress matrix (issue #9, docs/fsei.md): scene fsi at the defaults (the
# calibrated setting, `coarse`) from t = 0 to END_PHASE of a beat (default 0.4: through the
# ejection to the aortic valve's closure) over heart rate x tissue stiffness (every Fung c
# scaled) x the fluid's step (its CFL target scaled: at the defaults the coupling interval is one
# fluid step, so x m of the automatic step = fluid.cfl BASE_CFL m; BASE_CFL is the calibrated
# default's 0.4 since session 42 (0.2 before: the older tables' x m is this x m/2); a CFL past
# the hard limit 1 is refused at input, which the table shows). Runs go PARALLEL at a time, one rank
# each. Each run must either complete with finite metrics or stop with a diagnosis naming the
# module, the place and the time; anything else (a crash, a NaN metric, a hang past TIMEOUT_S) is
# marked BAD. A step level cN instead scales the coupling step: N of the fluid's stable steps (at
# CFL BASE_CFL since session 43; at CFL 0.2 before, the older tables' cN) per synchronisation interval (fsei.fluid_steps_per_interval, 1..8; the intervals' cap
# fsei.sync_step_ms raised N-fold from 0.1 ms with it, as the fluid's 0.1 ms), so the shells and
# the loads see the fluid N times less often (the multirate coupling's added-mass limit). The
# stiffness factor scales each tissue's Fung c from its value at the defaults (the table's, the
# aorta's 4312 Pa from the calibrated layer) unless C_LV, C_LA, C_LEAFLETS or C_AORTA (Pa) give
# another base. EXTRA adds path=value settings to every run; RATES, STIFFNESS
# and STEPS choose the levels of the full factorial design, or DESIGN lists the runs of a reduced
# one as heart_rate:stiffness:step triples (e.g. DESIGN="40:4:1 180:0.5:1"), longest first.
#   [END_PHASE=0.4] [RATES="40 70 180"] [STIFFNESS="0.5 1 4"] [STEPS="0.5 1 2 4"] [DESIGN=...] [BASE_CFL=0.4]
#   [PARALLEL=2] [LOGS=DIR (keep each run's N.err samples, N.out metrics and N.row table row)]
#   bench/coupling/fsei_stress.sh [build/bin/fsei_case] > table.md
set -u
exe=${1:-build/bin/fsei_case}
end_phase=${END_PHASE:-0.4}
base_cfl=${BASE_CFL:-0.4}  # the automatic step's CFL: the calibrated default fluid.cfl
timeout_s=${TIMEOUT_S:-14400}
if [ -n "${LOGS:-}" ]; then  # keep each run's samples (N.err) and metrics (N.out) there
  mkdir -p "$LOGS" && work=$(cd "$LOGS" && pwd)
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi
run_one() {
  local hr=$1 k=$2 m=$3 id=$4
  local cfl end_ms step_args step_label
  end_ms=$(awk -v p="$end_phase" -v hr="$hr" 'BEGIN { printf "%.10g", p * 60000 / hr }')  # 10 digits: END_PHASE=1 is a whole beat
  if [[ $m == c* ]]; then  # the coupling step: cN = N fluid steps (each at CFL BASE_CFL) per interval
    cfl=$base_cfl
    step_args=("fluid.cfl=$cfl" "fsei.fluid_steps_per_interval=${m#c}"
      "fsei.sync_step_ms=$(awk -v n="${m#c}" 'BEGIN { printf "%g", 0.1 * n }')")
    step_label="coupling x${m#c} (${m#c} fluid steps per interval, CFL $cfl)"
  else
    cfl=$(awk -v m="$m" -v b="$base_cfl" 'BEGIN { printf "%g", b * m }')
    step_args=("fluid.cfl=$cfl")
    step_label="x$m (CFL $cfl)"
  fi
  local args=(fsi "fsei.end_time_ms=$end_ms" "heart_rate_bpm=$hr" "${step_args[@]}")
  # shellcheck disable=SC2206
  args+=(${EXTRA:-})
  for t in lv la mitral_leaflets aortic_leaflets aorta; do
    local c
    case $t in lv) c=${C_LV:-13.3} ;; la) c=${C_LA:-12.1} ;; mitral_leaflets | aortic_leaflets) c=${C_LEAFLETS:-3702} ;;
      aorta) c=${C_AORTA:-4312} ;; esac
    args+=("tissue.$t.fung_c_pa=$(awk -v c="$c" -v k="$k" 'BEGIN { printf "%g", c * k }')")
  done
  local t0=$SECONDS
  OMP_NUM_THREADS=1 timeout "$timeout_s" "$exe" "${args[@]}" > "$work/$id.out" 2> "$work/$id.err" < /dev/null
  local rc=$?
  local wall=$((SECONDS - t0))
  local verdict
  if [ $rc -eq 0 ]; then
    if grep -qiE "= (-?nan|-?inf)" "$work/$id.out"; then verdict="BAD: completed with a non-finite metric"; else
      verdict="completed: LV peak $(awk '/^lv_pressure_max_mmhg/ {print $3}' "$work/$id.out") mmHg, LV volume down to $(awk '/^lv_volume_min_ml/ {print $3}' "$work/$id.out") ml, aortic peak flow $(awk '/^aortic_flow_max_ml_s/ {print $3}' "$work/$id.out") ml/s, $(awk '/^coupling_passes / {print $3}' "$work/$id.out") passes"; fi
  elif [ $rc -eq 124 ]; then
    verdict="BAD: no answer within ${timeout_s} s"
  elif grep -q "unstable run in module" "$work/$id.err"; then
    verdict=$(grep "unstable run in module" "$work/$id.err" | tail -n 1 |
      sed -E "s/.*module '([a-z_]+)' at (.*), t = ([0-9.e-]+) s: (.*)/stopped: \1 at \2, t = \3 s: \4/" |
      sed -E 's/ \(stress-free position [^)]*\)//; s/; substep dt.*//' | cut -c1-220)
  elif grep -q "out of range\|is not one of" "$work/$id.err"; then
    verdict="refused at input: $(grep -m 1 "out of range\|is not one of" "$work/$id.err" | cut -c1-160)"
  else
    verdict="BAD: exit $rc: $(tail -n 1 "$work/$id.err" | cut -c1-120)"
  fi
  verdict=${verdict//|/\\|}  # a markdown table cell
  local last
  last=$(grep "^fsi t_ms" "$work/$id.err" | tail -n 1 | awk '{print $3}')
  local row
  row=$(printf '| %s | x%s | %s | %s of %s | %s | %s s |' "$hr" "$k" "$step_label" "${last:-0}" "$end_ms" "$verdict" "$wall")
  echo "$row"
  echo "$row" > "$work/$id.row"  # the run's row as soon as it ends (the table below is sorted at the end)
}
export -f run_one
export exe end_phase base_cfl timeout_s work EXTRA C_LV C_LA C_LEAFLETS C_AORTA
echo "| heart rate (bpm) | stiffness | step | last sample (ms) | outcome | wall |"
echo "|---|---|---|---|---|---|"
design() {  # one "heart_rate stiffness step id" line per run
  local id=0
  if [ -n "${DESIGN:-}" ]; then
    for t in $DESIGN; do id=$((id + 1)); echo "${t//:/ } $id"; done
  else
    for hr in ${RATES:-40 70 180}; do for k in ${STIFFNESS:-0.5 1 4}; do for m in ${STEPS:-0.5 1 2 4}; do
      id=$((id + 1)); echo "$hr $k $m $id"
    done; done; done
  fi
}
design | xargs -P "${PARALLEL:-2}" -L 1 bash -c 'run_one "$@"' _ | sort -t'|' -k2,2n -k3,3 -k4,4
