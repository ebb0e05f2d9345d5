#!/usr/bin/env bash
# What a user of `mvcoba-train` gets: the default preset (6000 actions), seed 0, evaluated like the
# reproduction (every shipped suite, 5 runs per case, both protocols); resumable: run again after a
# stop. Run before the default pushed 5 cm (f6b2cff), so the push is set; the config is the same.
cd /work/win-tree
export PYTHONPATH=/work/win-tree PATH=/work/main/.venv/bin:$PATH
w=/work/pretrained-short log=/work/pretrained-short/runs.txt
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> $log
if [ ! -f $w/mvcoba-s0/eval_summary.json ]; then
  [ -d $w/mvcoba-s0/checkpoints ] && again=--resume || again=--overwrite
  mvcoba-train --set env.push_length=0.05 --workdir $w/mvcoba-s0 $again > $w/train.log 2>&1 || { echo "train rc $?" >> $log; exit 1; }
fi
echo "trained $(date -u +%FT%TZ)" >> $log
for protocol in frozen online; do
  [ -f $w/eval-$protocol/done ] && continue
  flag=; [ $protocol = online ] && flag=--online
  mvcoba-eval --checkpoint $w/mvcoba-s0 --suite random ordered occluded vpg --runs 5 \
    --out $w/eval-$protocol --resume $flag > $w/eval-$protocol.log 2>&1 \
    && touch $w/eval-$protocol/done || { echo "eval $protocol rc $?" >> $log; exit 1; }
  echo "evaluated $protocol $(date -u +%FT%TZ)" >> $log
done
echo "end $(date -u +%FT%TZ)" >> $log
# Landed with: bash experiments/land_pretrained.sh /work/pretrained-short ea15ee5
