#!/usr/bin/env bash
# Interior detection on minibrot views it was not tuned to: for four shipped locations
# (scenes/locations/), the lowest-period minibrot `deepfield find` finds in an 800x600 view
# around the location's centre (at zoom 1e95 for e401 and e1000, 1e90 for golden-spider and
# heaven), framed three times tighter than `find` frames it (so that about half the view is
# interior), at a limit of 10^7 iterations; then `examples/interior_cost` times every
# sample with detection against the exterior samples alone (the view "costs N times its
# exterior": the first line's time over the "exterior alone, detection off" one).
#
#   scripts/interior-views.sh [ROUNDS]   # default 2
set -euo pipefail
rounds=${1:-2}
cd "$(dirname "$0")/.."
cargo build --release --bin deepfield --example interior_cost
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for spec in e401:1e95 e1000:1e95 golden-spider:1e90 heaven:1e90; do
  name=${spec%%:*}
  zoom=${spec#*:}
  target/release/deepfield find "scenes/locations/$name.toml" --zoom "$zoom" --max-iter 10000000 \
    --size 800x600 -o "$out/$name.toml" > /dev/null
  # The zoom three times tighter ("M.MMMMMMeE" as `find` writes it).
  python3 - "$out/$name.toml" <<'PY'
import re, sys
path = sys.argv[1]
text = open(path).read()
m = re.search(r'zoom = "([0-9.]+)e([0-9+-]+)"', text)
text = text.replace(m.group(0), 'zoom = "%.6fe%s"' % (float(m.group(1)) * 3, m.group(2)))
open(path, "w").write(text)
PY
  echo "== $name: $(head -1 "$out/$name.toml" | sed 's/^# deepfield find: //')"
  target/release/examples/interior_cost "$out/$name.toml" "$rounds" --quick | tail -n +3
done
