#!/usr/bin/env bash
# The three test protocols on the reproduction's MV-COBA seeds (the default preset at 5f3edc9, the same parameters as the
# recipe study's nofresh_occlusion), occluded suite, 5 runs per case, then their join.
set -e
cd /work/main
. .venv/bin/activate
R=/work/reproduction/runs
echo "start $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD)"
for proto in no-repeat frozen online; do
  flag=""; [ "$proto" = online ] && flag="--online"; [ "$proto" = no-repeat ] && flag="--no-repeat"
  mvcoba-eval --checkpoint $R/mvcoba-s0 $R/mvcoba-s1 $R/mvcoba-s2 --suite occluded --runs 5 $flag --out /work/protocols2/$proto --resume
done
mvcoba-eval --tables /work/protocols2/frozen /work/protocols2/online /work/protocols2/no-repeat --out /work/protocols2/joined --overwrite
echo "end $(date -u +%FT%TZ)"
