#!/usr/bin/env bash
# The reproduction with the default preset of 5f3edc9 (the authors recipe without fresh transitions, a quarter of the drops occluded), from a worktree there;
# resumable: run this again after a stop and it continues where it was.
cd /work/repro-tree
export PYTHONPATH=/work/repro-tree PATH=/work/main/.venv/bin:$PATH
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)" >> /work/reproduction/runs.txt
# PROTOCOLS=frozen runs the frozen protocol alone (its comparison.md written when it ends)
mvcoba-reproduce --workdir /work/reproduction/runs --out /work/reproduction/tables --protocols ${PROTOCOLS:-frozen online}
rc=$?  # before the date's command substitution resets it
echo "end $(date -u +%FT%TZ) rc $rc" >> /work/reproduction/runs.txt
