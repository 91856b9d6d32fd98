#!/usr/bin/env bash
# Every generated results page of docs/, rerun from nothing (about 3 hours on 2 cores):
#
#     bash tools/regenerate_pages.sh [results-dir]
#
# Each step is the command its page names in its header, run on fresh stores (the
# results directory must not exist: nothing earlier is resumed); each page's header
# records how long its command took. Then the quoted blocks of the README and the
# analysis pages are rewritten (python tools/update_docs.py). `make bench` writes
# docs/speed-run.md apart (timings want a quiet machine).
set -euo pipefail
cd "$(dirname "$0")/.."
R=${1:-results}
if [ -e "$R" ]; then
    echo "regenerate_pages: $R exists; give a new directory (nothing is resumed)" >&2
    exit 2
fi
BIN=.venv/bin
export PYTHONPATH=src
took() { local s=$(( $(date +%s) - $1 )); echo "$((s / 60)) min $((s % 60)) s"; }

t=$(date +%s)
$BIN/python studies/tune.py --episodes 100 --workers 2
$BIN/python studies/tune.py --methods copi-predictive --families crowd,indoor --episodes 150 \
    --out docs/tuning-predictive.md

t=$(date +%s)
$BIN/copi reproduce -o "$R/"
$BIN/python tools/report_page.py "$R/report.md" docs/reproduce.md \
    --title "The paper's experiments, as \`copi reproduce\` reports them" \
    --command "copi reproduce -o results/ (seed 0, $(took "$t") on 2 cores)" \
    --about "The report \`copi reproduce\` writes; [the experiments, read](analysis/experiments.md) explains it."

$BIN/python studies/ceilings.py --bench "$R/ceilings" --episodes 200 --oracle-episodes 200
# on the ceilings' store: the bounds page with the RL rows (its rl.md is overwritten next)
$BIN/python studies/rl_experiments.py --bench "$R/ceilings" --episodes 200 --games 200
# the ceilings page again, on the store the RL rows are in now (it resumes: no episode reruns)
$BIN/python studies/ceilings.py --bench "$R/ceilings" --episodes 200 --oracle-episodes 200
$BIN/python studies/rl_experiments.py --bench "$R/rl-bench" --episodes 200 --games 200

t=$(date +%s)
D="copi-predictive,tracked-mpc,compass-guard@map,copi-learnt@map,dwa@map"
W=src/copi/data/worlds/dense-crowds.json
$BIN/copi benchmark -o "$R/bench-dense-crowds" --world-file $W --episodes 120 --workers 2 \
    --methods "$D" --against compass-guard
$BIN/python tools/benchmark_page.py "$R/bench-dense-crowds" docs/benchmark-dense-crowds.md \
    --what "crowd worlds no method was tuned on (the six dense-crowds worlds, 120 episodes)" --against compass-guard \
    --command "\`copi benchmark -o results/bench-dense-crowds --world-file $W --episodes 120 --workers 2 --methods $D --against compass-guard\` (seed 0; $(took "$t") on 2 cores)"

t=$(date +%s)
F="copi-predictive,tracked-mpc,model-oracle,compass-guard@map"
$BIN/copi benchmark -o "$R/crowd-power" --families crowd --episodes 800 --seed 2 --methods "$F" \
    --against tracked-mpc --workers 2
$BIN/python tools/benchmark_page.py "$R/crowd-power" docs/benchmark-crowd-fresh.md \
    --what "crowd episodes of a seed no method was tuned on (seed 2, 800 episodes)" --against tracked-mpc \
    --command "\`copi benchmark -o results/crowd-power --families crowd --episodes 800 --seed 2 --methods $F --against tracked-mpc --workers 2\` ($(took "$t") on 2 cores, the predictive preset's capabilities learnt first)"
$BIN/python studies/predictive_gap.py --episodes 800 --draws 2
$BIN/python studies/predictive_perception.py
$BIN/python studies/predictive_repairs.py --episodes 800 --draws 2
$BIN/python studies/predictive_horizon.py --episodes 600 --indoor-episodes 300 --draws 2
$BIN/python studies/predictive_failures.py --episodes 200
$BIN/python studies/predictive_cost.py --episodes 100

t=$(date +%s)
S=copi-learnt@sensor,copi-predictive@sensor,compass-guard@sensor,straight@sensor
S=$S,copi-learnt@sensor:mapping,compass-guard@sensor:mapping,copi-predictive@sensor:mapping
$BIN/copi benchmark -o "$R/predictive-sensor" --families star,polygon,indoor,maps,crowd \
    --methods "$S" --against copi-learnt --episodes 200 --seed 0 --workers 2
$BIN/python tools/benchmark_page.py "$R/predictive-sensor" docs/benchmark-sensor.md \
    --what "level \`sensor\`: no map, no position; copi-predictive beside copi-learnt" --against copi-learnt \
    --command "\`copi benchmark -o results/predictive-sensor --families star,polygon,indoor,maps,crowd --methods $S --against copi-learnt --episodes 200 --seed 0 --workers 2\` (seed 0; $(took "$t") on 2 cores; copi-predictive finds its own way at \`sensor\`, so its two rows are the same episodes run twice, each paired with copi-learnt under that strategy)"

t=$(date +%s)
$BIN/copi benchmark -o "$R/bench-ablations" --episodes 500 --workers 2 --methods ablations
$BIN/python tools/benchmark_page.py "$R/bench-ablations" docs/benchmark-ablations.md \
    --what "the learnt preset's ablations, 500 episodes" \
    --command "\`copi benchmark -o results/bench-ablations --episodes 500 --workers 2 --methods ablations\` (seed 0; $(took "$t") on 2 cores)"

M=copi-faithful@sensor,copi-extended@sensor,copi-learnt@sensor,straight@sensor,compass-guard@sensor,vfh@sensor,dwa@sensor,tangent-bug@sensor
M=$M,copi-faithful@sensor:mapping,copi-extended@sensor:mapping,copi-learnt@sensor:mapping,straight@sensor:mapping
M=$M,compass-guard@sensor:mapping,vfh@sensor:mapping,dwa@sensor:mapping,tangent-bug@sensor:mapping
t=$(date +%s)
$BIN/copi benchmark -o "$R/bench-mapping" --episodes 200 --methods "$M"
$BIN/python tools/benchmark_page.py "$R/bench-mapping" docs/benchmark-mapping.md \
    --what "200 episodes at level sensor, heading for the goal and with a map built on the fly" \
    --command "\`copi benchmark -o results/bench-mapping --episodes 200 --methods $M\` (seed 0; $(took "$t") on 2 cores)"

$BIN/python studies/crowdnav.py --bench "$R/crowdnav" --episodes 500 --out docs/crowdnav.md

$BIN/python studies/landmarks.py --seeds 10 --workers 2 --out docs/landmarks.md
$BIN/python studies/landmarks_effect.py --episodes 200 --seeds 0,1,2,3,4 \
    --out docs/landmarks-effect.md

t=$(date +%s)
$BIN/copi learn -o "$R/capabilities-learnt.npz"
L="--family maps --worlds 20 --tasks 50 --seed 3 --methods copi-learnt,copi-learnt-continual,copi-learnt@sensor:mapping,compass-guard"
# shellcheck disable=SC2086
$BIN/copi lifelong "$R/capabilities-learnt.npz" -o "$R/lifelong-maps/run.sqlite" $L
$BIN/python tools/report_page.py "$R/lifelong-maps/run.md" docs/lifelong-maps.md \
    --title "Experiment 3 in the maps family: continual contexts in unfamiliar worlds" \
    --command "copi lifelong results/capabilities-learnt.npz -o results/lifelong-maps/run.sqlite $L ($(took "$t") on 2 cores)"

$BIN/python studies/families.py --n 200 --seed 0 --pictures docs --into docs/families.md
$BIN/python tools/update_docs.py
echo "regenerate_pages: every page rewritten from $R"
