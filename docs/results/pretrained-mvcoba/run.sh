#!/usr/bin/env bash
# What a user of `mvcoba-train` gets: the default preset (6000 actions), seed 0, trained from a
# worktree at the commit that last changed training's numerics (70f7adb: pushes cut at the
# workspace's edge), then evaluated from a tree that names the development suites (395c698) on
# every development suite and VPG's cases, 5 runs per case, frozen then online; resumable: run
# again after a stop. Landed with experiments/land_pretrained.sh WORKDIR TRAINED_AT_COMMIT.
w=/work/pre log=/work/pre/runs.txt
export PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
(cd /work/tree-cut && export PYTHONPATH=/work/tree-cut
 echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> $log
 if [ ! -f $w/mvcoba-s0/eval_summary.json ]; then
   [ -d $w/mvcoba-s0/checkpoints ] && again=--resume || again=--overwrite
   mvcoba-train --workdir $w/mvcoba-s0 $again > $w/train.log 2>&1 || { echo "train rc $?" >> $log; exit 1; }
 fi
 echo "trained $(date -u +%FT%TZ)" >> $log) || exit 1
cd /work/tree-sealed && export PYTHONPATH=/work/tree-sealed
echo "eval start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> $log
for protocol in frozen online; do
  [ -f $w/eval-$protocol/done ] && continue
  flag=; [ $protocol = online ] && flag=--online
  mvcoba-eval --checkpoint $w/mvcoba-s0 --suite dev-random dev-ordered dev-occluded vpg --runs 5 \
    --out $w/eval-$protocol --resume $flag > $w/eval-$protocol.log 2>&1 \
    && touch $w/eval-$protocol/done || { echo "eval $protocol rc $?" >> $log; exit 1; }
  echo "evaluated $protocol $(date -u +%FT%TZ)" >> $log
done
