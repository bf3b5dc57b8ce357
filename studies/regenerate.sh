#!/usr/bin/env bash
# Regenerate every committed study output (full mode) with the current code, cheapest first and the
# long FE studies last.  Each study writes its outputs and a sidecar run.json (commit, dirty flag,
# arguments, package versions; studies/_provenance.py) under studies/out/<name>/.
#
#   studies/regenerate.sh                 # all of them (several hours on a 2-core machine)
#   studies/regenerate.sh profile_sweep manchester_a22   # only these (names as in the list below)
#
# Run from anywhere; uses the repository's .venv when present.  Every study runs under `nice -n 5`
# with one BLAS thread; its console output goes to $LOGDIR/<name>.log (default
# /tmp/conformal_regenerate, outside the tree).  Failures do not
# stop the others; the script exits 1 if any failed.  Timing columns in the outputs are wall times
# of the machine it runs on: regenerate them on an idle machine.
#
# Notes
# * creep_coefficients rewrites conformal/data/kalker_c33.csv and kalker_coefficients_computed.csv
#   (the same values unless conformal.theories.c33 changed; the C33 convergence header lines of
#   c33_convergence are kept) - review `git diff conformal/data` afterwards.
# * c33_convergence also writes the header of conformal/data/kalker_c33.csv (values unchanged).
# * fe_influence_speed_error: the committed outputs (studies/out/fe_influence_speed_error.*,
#   fe_kernel_*.npy) are those of its --quick mode (docs/validation/fe-influence.md).
# * FE studies cache their influence numbers ($CONFORMAL_CACHE): a second run is much faster.
set -u
cd "$(dirname "$0")/.." || exit 2
[ -f .venv/bin/activate ] && . .venv/bin/activate
export OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg
PY=${PYTHON:-python}

# name | command line (arguments after the script); in run order
STUDIES=(
  "profile_sweep|studies/profile_sweep.py"                          # ~1 min
  "fast_theories_benchmark|studies/fast_theories_benchmark.py"      # ~1 min
  "creep_coefficients|studies/creep_coefficients.py"                # ~3 min, also conformal/data
  "manchester_a22|studies/manchester_a22.py"                        # ~2 min
  "contact_conformal|studies/contact_conformal.py"                  # ~15 min (CONTACT testbank)
  "halfspace_scaling|studies/halfspace_scaling.py"                  # ~5 min (timings)
  "steady_rolling_speed|studies/steady_rolling_speed.py"            # minutes (timings)
  "performance|studies/performance.py"                              # if present
  "c33_convergence|studies/c33_convergence.py"                      # minutes
  "creep_table_accuracy|studies/creep_table_accuracy.py"            # ~10 min
  "creep_table_scaling|studies/creep_table_scaling.py"              # ~10 min
  "seed_wheelset|studies/seed_wheelset.py"                          # 15-25 min
  "flange_contact|studies/flange_contact.py"                        # ~10 min (FE, cached after)
  "speed_vs_error|studies/speed_vs_error.py"                        # ~15 min (FE)
  "fe_body_size|studies/fe_body_size.py"                            # ~15 min (FE)
  "groove_pitch_fe|studies/groove_pitch_fe.py --forms fe,planar,blanco3,blanco4,default,fe_without_xn,fe_without_sn,fe_uncoupled,fe_blanco3_coupling,fe_blanco4_coupling,blanco4_fe_coupling"   # ~60 min (FE; the --scale 2 rows are kept)
  "fe_influence_speed_error|studies/fe_influence_speed_error.py --quick"   # ~5 min (FE)
  "fe_contact_convergence|studies/fe_contact_reference.py --convergence"   # ~10 min (FE contact)
  "fe_contact_comparison|studies/fe_contact_reference.py --comparison"     # ~15 min (FE contact)
)

LOGDIR=${LOGDIR:-/tmp/conformal_regenerate}
mkdir -p "$LOGDIR"
failed=()
for entry in "${STUDIES[@]}"; do
  name=${entry%%|*}
  cmd=${entry#*|}
  script=${cmd%% *}
  if [ $# -gt 0 ]; then
    want=0
    for n in "$@"; do [ "$n" = "$name" ] && want=1; done
    [ $want = 1 ] || continue
  fi
  if [ ! -f "$script" ]; then
    echo "skip $name: $script not found"
    continue
  fi
  echo "=== $name: $PY $cmd  ($(date -u +%H:%M:%S) UTC)"
  start=$(date +%s)
  # shellcheck disable=SC2086  # cmd holds the script and its arguments
  if nice -n 5 "$PY" $cmd > "$LOGDIR/$name.log" 2>&1; then
    echo "    done in $(( $(date +%s) - start )) s"
  else
    echo "    FAILED (exit $?), see $LOGDIR/$name.log"
    failed+=("$name")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "failed: ${failed[*]}"
  exit 1
fi
