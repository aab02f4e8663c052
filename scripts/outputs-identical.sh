#!/bin/bash
# Shows that two builds of gtn write the same bytes: every shared dataset converted with the default
# settings and with --levels 0, exported to .vtu, .vtk and TetGen (level 0 and a ratio), rendered to a
# PNG, and the text reports of info and validate. Prints one line per output and exits 1 when any
# output differs.
#   scripts/outputs-identical.sh OLD_GTN NEW_GTN [DATA_DIR]
# OLD_GTN and NEW_GTN may be relative paths and may have any name: each is run as `gtn` from a folder
# of its own (a .gtn file records the command line that wrote it, program name included).
set -u
if [ $# -lt 2 ]; then echo "usage: $0 OLD_GTN NEW_GTN [DATA_DIR]" >&2; exit 2; fi
for b in "$1" "$2"; do [ -x "$b" ] || { echo "$0: $b: not an executable" >&2; exit 2; }; done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/bin-old" "$work/bin-new"
ln -s "$(realpath "$1")" "$work/bin-old/gtn"
ln -s "$(realpath "$2")" "$work/bin-new/gtn"
data=${3:-${GTN_DATA_DIR:-$(cd "$(dirname "$0")/.." && pwd)/../shared/data}}
inputs=(
  "plot3d/bluntfinxyz.bin plot3d/bluntfinq.bin"
  "plot3d/combxyz.bin plot3d/combq.bin"
  "vtk/spx.vtk"
  "tetgen/cornell_spheres.1.node"
  "tetgen/cornellbox_orig.1.node"
  "medit/bunny.mesh"
  "vtu/lv_guccione.vtu"
  "vtu/raptorTetra_19409.vtu"
  "vtu/Ossicles.vtu"
  "vtu/fire_ug.vtu"
)
# run SIDE NAME ARGS...: runs one build's gtn in its own folder; the outputs keep the same names.
run() {
  local side=$1 name=$2; shift 2
  mkdir -p "$work/$side"
  (cd "$work/$side" && PATH="$work/bin-$side:$PATH" gtn "$@" >"$name.out" 2>&1; echo "exit $?" >>"$name.out")
}
differ=0
compare() {
  for f in "$work"/old/*; do
    local b; b=$(basename "$f")
    if ! cmp -s "$f" "$work/new/$b"; then echo "DIFFERENT $b"; differ=1; else echo "same      $b"; fi
  done
  rm -rf "$work"/old "$work"/new
}
for spec in "${inputs[@]}"; do
  read -r -a files <<<"$spec"
  paths=(); for f in "${files[@]}"; do paths+=("$data/$f"); done
  n=$(basename "${files[0]}"); n=${n%%.*}
  for side in old new; do
    run $side convert-$n convert "${paths[@]}" -o $n.gtn -q
    run $side convert0-$n convert "${paths[@]}" -o $n.l0.gtn --levels 0 -q
    run $side info-$n info $n.gtn
    run $side validate-$n validate $n.gtn
    run $side export-$n export $n.gtn -o $n.vtu
    run $side exportvtk-$n export $n.gtn -o $n.r5.vtk --ratio 0.5
    run $side exportele-$n export $n.gtn -o $n.ele
    run $side render-$n render $n.gtn -o $n.png --size 128
  done
  # Timings in reports differ between runs: compare the files and reports without their time lines.
  for side in old new; do sed -i -E '/[0-9.]+ ?(ms|s)\b|seconds|per second/d' "$work/$side"/*.out; done
  compare
done
exit $differ
