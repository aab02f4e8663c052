#!/bin/sh
# End-to-end render timings (file to PNG) of the integrated and generic pipelines, as the paper's
# Figure 5 and Table 2: blunt fin at 256x256 over simplification ratios, then per stored level at
# 128x128. Usage: bench/render/render_bench.sh [BUILD_DIR] [DATA_DIR]
# Writes a table on standard output; images and the .gtn go to a temporary directory.
set -eu
build=${1:-build}
data=${2:-../shared/data}
gtn="$build/gtn"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

src="$data/plot3d/bluntfinxyz.bin $data/plot3d/bluntfinq.bin"
# shellcheck disable=SC2086
"$gtn" convert $src -o "$work/blunt.gtn" >/dev/null
input="$work/blunt.gtn"

ms() { sed -n 's/.*"total_ms": \([0-9.]*\).*/\1/p'; }
field() { sed -n "s/.*\"$1\": \([0-9.]*\).*/\1/p"; }

echo "# blunt fin, 256x256, density, volume sampling: end-to-end ms (file to PNG)"
echo "ratio integrated generic tets_rendered peak_tets_held rmse_vs_full"
"$gtn" render "$input" -o "$work/full.png" --field density --size 256x256 >/dev/null
for r in 0 0.5 0.75 0.9 0.95 0.99; do
  # A ratio needs mip levels or a merge tree in the file: skip it when the file has none.
  ji=$("$gtn" render "$input" -o "$work/i.png" --field density --size 256x256 --ratio "$r" --json 2>/dev/null) || continue
  jg=$("$gtn" render "$input" -o "$work/g.png" --field density --size 256x256 --ratio "$r" --pipeline generic --json)
  rmse=$("$gtn" compare "$work/full.png" "$work/i.png" --json | field rmse)
  echo "$r $(echo "$ji" | ms) $(echo "$jg" | ms) $(echo "$ji" | field tets_rendered) $(echo "$ji" | field peak_tets_held) $rmse"
done

echo "# blunt fin, 128x128, per stored level (Table 2): end-to-end ms"
echo "level tets integrated"
i=0
while ji=$("$gtn" render "$input" -o "$work/l.png" --field density --size 128x128 --level $i --json 2>/dev/null); do
  echo "$i $(echo "$ji" | field tets_decoded) $(echo "$ji" | ms)"
  i=$((i + 1))
done
