#!/usr/bin/env bash
# Issue 65's claim: VARIANT (of experiments/recipe_variants.py) trained on seeds 0-4 at 3000
# actions (the screen's seeds 0 and 1 reused), every seed evaluated frozen on the reproduction's
# suites with its runs and cap (random ordered occluded vpg, 5 runs per case, 60 actions), then
# the joined tables beside the 5-seed reproduction. Resumable. From /work/study-tree.
set -u
variant=$1
cd /work/study-tree && . .venv/bin/activate && export PYTHONPATH=/work/study-tree
args=$(python -c "import sys; sys.path.insert(0, 'experiments'); import recipe_study as r; print(' '.join(r.VARIANTS['$variant']))") || exit 1
[ -n "$args" ] || { echo "no arguments for $variant"; exit 1; }
echo "$variant: mvcoba-train $args"
log=/work/study-winning/claim-$variant.jsonl
for seed in 0 1 2 3 4; do
  run=/work/study-winning/$variant/mvcoba-s$seed
  [ -f "$run/eval_summary.json" ] && continue
  flag=--overwrite; [ -d "$run/checkpoints" ] && flag=--resume
  start=$(date +%s)
  mvcoba-train $args --method mvcoba --seed $seed --workdir "$run" --eval-actions 1 $flag \
    > /work/study-winning/train-$variant-s$seed.log 2>&1
  echo "{\"what\": \"train-$variant-s$seed\", \"rc\": $?, \"wall_s\": $(( $(date +%s) - start )), \"commit\": \"$(git rev-parse --short HEAD)\", \"ended\": \"$(date)\"}" >> $log
done
out=/work/study-winning/claim-$variant
start=$(date +%s)
mvcoba-eval --checkpoint /work/study-winning/$variant/mvcoba-s{0,1,2,3,4} \
  --suite random ordered occluded vpg --runs 5 --out $out/eval --resume > $out-eval.log 2>&1
echo "{\"what\": \"eval-$variant\", \"rc\": $?, \"wall_s\": $(( $(date +%s) - start )), \"ended\": \"$(date)\"}" >> $log
mvcoba-eval --tables $out/eval /work/main/docs/results/reproduction --out $out/tables --overwrite \
  > $out-tables.log 2>&1
echo "claim done: $(date)"
