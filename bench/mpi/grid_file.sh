# Sourced by bench_mpi.sh and bench_mpi_write.sh, after they set size, build and name (for messages):
# checks the tools, makes the work directory ($BENCH_MPI_DIR when set, else a temporary one removed at
# exit) and, unless it is there already, $file: the sample grid at size^3 points (gtn-make-sample),
# converted with `gtn convert --levels 0 --no-merge-tree --piece-tets 524288` (level 0 alone, no
# ranking; pieces of at most 2^19 tetrahedra, so that ranks have pieces to share: at the default bound
# a grid is one structured piece). Sets gtn, plugin, work and file.
gtn="$build/gtn"
plugin=$(find "$build" -name 'GatunPlugin.so' | head -n 1)
for tool in pvbatch mpirun; do
  command -v $tool >/dev/null || { echo "$name: $tool not found" >&2; exit 2; }
done
[ -x "$gtn" ] && [ -x "$build/gtn-make-sample" ] && [ -n "$plugin" ] ||
  { echo "$name: build gtn_cli, gtn_make_sample and GatunPlugin in $build first" >&2; exit 2; }
if [ -n "${BENCH_MPI_DIR:-}" ]; then
  work=$BENCH_MPI_DIR
  mkdir -p "$work"
else
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
fi
file="$work/grid$size.gtn"
if [ ! -f "$file" ]; then
  "$build/gtn-make-sample" "$work" "$size" "$size" "$size" >/dev/null
  t0=$(date +%s.%N)
  "$gtn" convert "$work/sample.xyz" "$work/sample.q" --levels 0 --no-merge-tree --piece-tets 524288 -o "$file" \
    >/dev/null 2>&1
  t1=$(date +%s.%N)
  rm -f "$work/sample.xyz" "$work/sample.q"
  echo "converted ${size}^3 in $(echo "$t1 - $t0" | bc) s"
fi
