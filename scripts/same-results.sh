#!/usr/bin/env bash
# Checks that the working tree computes exactly what a base revision computes: for the shipped
# scenes (the rockfall in both methods, the two slopes) and a generated 100-block struck wall
# (0.5 s), `blocks.csv` and `contacts.csv` must be byte-identical and `summary.json` may differ
# only in its timings (`wall_seconds`, `timings`). Use it around any refactoring of the solver.
#
#   scripts/same-results.sh [BASE_REF]        (default BASE_REF: HEAD)
#   BASE_BIN=/path/to/dda3d scripts/same-results.sh   (compare against a binary built earlier)
#
# The base is built in a git worktree under target/same-results/ with its own target directory
# (the first build takes as long as a clean release build; later ones are incremental).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
work="$root/target/same-results"
mkdir -p "$work"

cargo build --release --quiet
new_bin="$root/target/release/dda3d"

if [ -n "${BASE_BIN:-}" ]; then
  base_bin="$BASE_BIN"
else
  ref="${1:-HEAD}"
  rev=$(git rev-parse --verify "$ref^{commit}")
  if [ -d "$work/src" ]; then
    git -C "$work/src" checkout --quiet --detach "$rev"
  else
    git worktree add --quiet --detach "$work/src" "$rev"
  fi
  (cd "$work/src" && CARGO_TARGET_DIR="$work/target" cargo build --release --quiet)
  base_bin="$work/target/release/dda3d"
fi

"$new_bin" generate column --blocks 100 --out "$work/wall100.toml" >/dev/null 2>&1
cases=(
  "rockfall-alm|scenes/rock_column_rockfall.toml|--method alm"
  "rockfall-penalty|scenes/rock_column_rockfall.toml|--method penalty"
  "slope-sliding|scenes/slope_sliding.toml|"
  "slope-stable|scenes/slope_stable.toml|"
  "wall100|$work/wall100.toml|--duration 0.5"
)
status=0
for c in "${cases[@]}"; do
  IFS='|' read -r name scene extra <<<"$c"
  for side in base new; do
    bin=$base_bin; [ "$side" = new ] && bin=$new_bin
    rm -rf "$work/$side/$name"
    # shellcheck disable=SC2086
    "$bin" run "$scene" $extra --quiet --out "$work/$side/$name" >/dev/null
  done
  same=ok
  for f in blocks.csv contacts.csv; do
    cmp -s "$work/base/$name/$f" "$work/new/$name/$f" || { same="DIFFERS in $f"; status=1; }
  done
  python3 - "$work/base/$name/summary.json" "$work/new/$name/summary.json" <<'PY' || { same="DIFFERS in summary.json"; status=1; }
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for s in (a, b):
    s.pop("wall_seconds", None); s.pop("timings", None)
if a != b:
    for k in sorted(set(a) | set(b)):
        if a.get(k) != b.get(k):
            print(f"  summary.json {k}: {a.get(k)} -> {b.get(k)}")
    sys.exit(1)
PY
  printf '%-18s %s\n' "$name" "$same"
done
exit $status
