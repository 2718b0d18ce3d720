#!/usr/bin/env bash
# The fsei stability stress matrix (issue #9, docs/fsei.md): scene fsi at `coarse` for END_MS
# (default 10 ms) over heart rate x tissue stiffness (every Fung c scaled) x coupling step
# (fsei.sync_step_ms and fluid.max_dt_ms, x1 = 0.1 ms), two runs at a time. Each run must either
# complete with finite metrics or stop with a diagnosis naming the module, the place and the
# time; anything else (a crash, a NaN metric, a hang past TIMEOUT_S) is marked BAD. EXTRA adds
# path=value settings to every run. The stiffness factor scales each tissue's Fung c from its base
# value, the default's unless C_LV, C_LA, C_LEAFLETS or C_AORTA (Pa) set another (a setting whose
# EXTRA changes a c must give it here too: the factor's c is set after EXTRA).
#   [END_MS=10] [EXTRA="fsei.aortic_pressure_mmhg=0"] [C_AORTA=4312] bench/coupling/fsei_stress.sh [build/bin/fsei_case] > table.md
set -u
exe=${1:-build/bin/fsei_case}
end_ms=${END_MS:-10}
timeout_s=${TIMEOUT_S:-900}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run_one() {
  local hr=$1 k=$2 m=$3 id=$4
  local sync
  sync=$(awk -v m="$m" 'BEGIN { printf "%g", 0.1 * m }')
  local args=(fsi "fsei.end_time_ms=$end_ms" "heart_rate_bpm=$hr" "fsei.sync_step_ms=$sync" "fluid.max_dt_ms=$sync")
  # shellcheck disable=SC2206
  args+=(${EXTRA:-})
  for t in lv la mitral_leaflets aortic_leaflets aorta; do
    local c
    case $t in lv) c=${C_LV:-13.3} ;; la) c=${C_LA:-12.1} ;; mitral_leaflets | aortic_leaflets) c=${C_LEAFLETS:-3702} ;;
      aorta) c=${C_AORTA:-11.3} ;; esac
    args+=("tissue.$t.fung_c_pa=$(awk -v c="$c" -v k="$k" 'BEGIN { printf "%g", c * k }')")
  done
  local t0=$SECONDS
  OMP_NUM_THREADS=1 timeout "$timeout_s" "$exe" "${args[@]}" > "$work/$id.out" 2> "$work/$id.err" < /dev/null
  local rc=$?
  local wall=$((SECONDS - t0))
  local verdict
  if [ $rc -eq 0 ]; then
    if grep -qiE "= (-?nan|-?inf)" "$work/$id.out"; then verdict="BAD: completed with a non-finite metric"; else
      verdict="completed, LV max $(awk '/^lv_pressure_max_mmhg/ {print $3}' "$work/$id.out") mmHg"; fi
  elif [ $rc -eq 124 ]; then
    verdict="BAD: no answer within ${timeout_s} s"
  elif grep -q "unstable run in module" "$work/$id.err"; then
    verdict=$(grep "unstable run in module" "$work/$id.err" | tail -n 1 |
      sed -E "s/.*module '([a-z_]+)' at (.*), t = ([0-9.e-]+) s: (.*)/stopped: \1 at \2, t = \3 s: \4/" |
      sed -E 's/ \(stress-free position [^)]*\)//; s/; substep dt.*//' | cut -c1-220)
  else
    verdict="BAD: exit $rc: $(tail -n 1 "$work/$id.err" | cut -c1-120)"
  fi
  verdict=${verdict//|/\\|}  # a markdown table cell
  local last
  last=$(grep "^fsi t_ms" "$work/$id.err" | tail -n 1 | awk '{print $3}')
  printf '| %s | x%s | x%s (%s ms) | %s | %s | %s s |\n' "$hr" "$k" "$m" "$sync" "${last:-0}" "$verdict" "$wall"
}
export -f run_one
export exe end_ms timeout_s work EXTRA C_LV C_LA C_LEAFLETS C_AORTA
echo "| heart rate (bpm) | stiffness | step | last sample (ms) | outcome | wall |"
echo "|---|---|---|---|---|---|"
id=0
for hr in 40 70 180; do for k in 0.5 1 4; do for m in 1 8; do
  id=$((id + 1)); echo "$hr $k $m $id"
done; done; done | xargs -P 2 -L 1 bash -c 'run_one "$@"' _ | sort -t'|' -k2,2n -k3,3 -k4,4
