#!/usr/bin/env bash
# Issue 81's screen: the objects preset against today's default at seeds 20 and 21 (whose default
# runs issue 80's screen trained: /work/study-80), validation only; resumable.
cd /work/tree-objects  # a worktree at the commit that added the `objects` variant
export PYTHONPATH=/work/tree-objects PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
V=docs/results/validation
mkdir -p /work/study-81-control && ln -sfn /work/study-80/cut_default /work/study-81-control/cut_default
python experiments/recipe_study.py --workdir /work/study-81-control --variants cut_default \
  --seeds 20 21 --runs 3 --suites $V/val-novel
python experiments/recipe_study.py --workdir /work/study-81 --variants objects --seeds 20 21 \
  --runs 3 --suites $V/val-novel $V/val-packed $V/val-heaps $V/val-occluded-high
