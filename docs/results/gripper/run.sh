#!/usr/bin/env bash
# Issue 82: today's default trained for each gripper preset (the RG2's runs are issue 80's
# cut_default at the same seeds), 2 seeds, evaluated on the development suites; resumable.
cd /work/tree-gripper  # a worktree at the commit that added the gripper variants
export PYTHONPATH=/work/tree-gripper PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
python experiments/recipe_study.py --workdir /work/study-82 --variants gripper_robotiq_2f85 \
  gripper_franka_hand --seeds 20 21 --runs 3 --suites dev-random dev-ordered dev-occluded
# The RG2's runs at the same seeds (issue 80's screen trained them) on the same suites.
mkdir -p /work/study-82-control && ln -sfn /work/study-80/cut_default /work/study-82-control/cut_default
python experiments/recipe_study.py --workdir /work/study-82-control --variants cut_default \
  --seeds 20 21 --runs 3 --suites dev-random dev-ordered dev-occluded
