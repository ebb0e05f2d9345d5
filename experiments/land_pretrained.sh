#!/usr/bin/env bash
# Lands what a user of `mvcoba-train` gets as pretrained/mvcoba: the default preset's run
# (WORKDIR/mvcoba-s0) with its figures from the evaluations beside it (WORKDIR/eval-frozen,
# WORKDIR/eval-online: every shipped suite, 5 runs per case) and the commit that trained it;
# the evaluations' tables go to docs/results/pretrained-mvcoba. course.json records the tiny
# preset's training fingerprint (`training.course_fingerprint`), which a test holds equal to
# today's: land it from a tree whose training numerics are the trained commit's.
#   bash experiments/land_pretrained.sh WORKDIR TRAINED_AT_COMMIT
set -euo pipefail
cd "$(dirname "$0")/.."
workdir=$1 commit=$2 dest=docs/results/pretrained-mvcoba
for protocol in frozen online; do
  [ -f "$workdir/eval-$protocol/done" ] || {
    echo "$workdir/eval-$protocol: the $protocol evaluation has not finished" >&2; exit 2; }
  mkdir -p "$dest/$protocol"
  cp "$workdir/eval-$protocol/results.json" "$workdir/eval-$protocol/results.md" "$dest/$protocol/"
done
rm -rf pretrained/mvcoba
mvcoba-export --checkpoint "$workdir/mvcoba-s0" --out pretrained/mvcoba --commit "$commit" \
  --results "$dest/frozen/results.json" "$dest/online/results.json"
rm pretrained/mvcoba/model.onnx
python - "$commit" <<'EOF'
import json, sys
from mvcoba_jax import runtime
runtime.setup()
from mvcoba_jax.config import resolve
from mvcoba_jax.learner.training import Trainer, course_fingerprint
calls = 2
record = {'preset': 'tiny', 'calls': calls, 'commit': sys.argv[1],
          'fingerprint': course_fingerprint(Trainer(resolve('tiny')), calls)}
open('pretrained/mvcoba/course.json', 'w').write(json.dumps(record, indent=1) + '\n')
EOF
