#!/usr/bin/env bash
# Issue 83's parity: the six shipped policies frozen and MV-COBA online on dev-occluded, 5 runs per
# case, evaluated by the code before the Decision object and the value tasks (088a9e1, the claim's
# worktree) and after them (AFTER, a worktree at the commit named in parity.md); then every run's
# counts compared (parity.json).
set -euo pipefail
AFTER=$1
export PATH=/work/main/.venv/bin:$PATH MVCOBA_JAX_CACHE=/work/main/.cache/jax
W=/work/parity-83
P="pretrained/mvcoba pretrained/mvcoba_2fcn pretrained/vpg pretrained/grasp_only pretrained/mvp pretrained/cpg"
for side in before after; do
  tree=/work/tree-claim
  [ $side = after ] && tree=$AFTER
  cd "$tree"
  PYTHONPATH=$tree mvcoba-eval --checkpoint $P --suite dev-occluded --runs 5 \
    --out $W/$side-frozen --resume
  PYTHONPATH=$tree mvcoba-eval --checkpoint pretrained/mvcoba --suite dev-occluded --runs 5 \
    --online --out $W/$side-online --resume
done
python - "$W" <<'PY'
import json, sys
w = sys.argv[1]
out = {}
for protocol in ('frozen', 'online'):
  before, after = (json.load(open(f'{w}/{s}-{protocol}/results.json')) for s in ('before', 'after'))
  for suite, rows in after.items():
    for label, row in rows.items():
      old = before[suite][label]
      out[f'{protocol} {suite} {label}'] = {
          'runs': sum(len(v) for v in row['runs'].values()),
          'identical': row['runs'] == old['runs'],
          'params_same': row['settings']['params'] == old['settings']['params'],
          'grasp_success': row['mean']['grasp_success'], 'completion': row['mean']['completion']}
print(json.dumps(out, indent=1))
PY
