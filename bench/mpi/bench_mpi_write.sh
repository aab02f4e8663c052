#!/bin/sh
# ParaView's MPI writing one .gtn from a distributed grid: GTNPartsWriter (each rank codes its share of
# level 0, rank 0 gathers the coded pieces and writes) against GTNWriter's gathering (rank 0 receives
# the whole grid and codes it; level 0 alone, so that both write the same level). The grid is the
# project's sample shape at SIZE^3 points (gtn-make-sample; 128 gives 12.3 million tetrahedra), stored
# with `gtn convert --levels 0 --no-merge-tree --piece-tets 524288` and read by the ranks (write_timed.py) before each write.
# Prints each run (rank 0's write time and peak memory), then the medians.
#
# Usage: bench/mpi/bench_mpi_write.sh [SIZE] [RANKS] [ROUNDS] [BUILD_DIR]
#   (defaults: 128, 2, 3, build). Needs pvbatch, mpirun and the plugin built (GatunPlugin).
#   The converted file stays in $BENCH_MPI_DIR when that is set (a later run with the same SIZE reuses it).
#   Timings are wall-clock on whatever else the machine is doing.
set -eu
size=${1:-128}
ranks=${2:-2}
rounds=${3:-3}
build=${4:-build}
here=$(cd "$(dirname "$0")" && pwd)
name=bench_mpi_write
. "$here/grid_file.sh"
results=""
i=1
while [ $i -le "$rounds" ]; do
  for mode in parts gather; do
    line=$(mpirun --allow-run-as-root --oversubscribe -np "$ranks" pvbatch "$here/write_timed.py" "$plugin" "$file" \
           "$mode" "$work/out-$mode.gtn" 2>/dev/null | grep '^write_s=')
    "$gtn" validate "$work/out-$mode.gtn" --against "$file" >/dev/null ||
      { echo "bench_mpi_write: $mode wrote a file unlike the source" >&2; exit 1; }
    bytes=$(stat -c %s "$work/out-$mode.gtn")
    echo "  round $i: $line bytes=$bytes"
    results="$results$line bytes=$bytes
"
  done
  i=$((i + 1))
done
python3 - "$results" <<'PY'
import statistics, sys
runs = {}
for line in sys.argv[1].strip().splitlines():
    f = dict(kv.split("=") for kv in line.split())
    runs.setdefault(f["mode"], []).append(f)
for mode, rs in runs.items():
    med = lambda k: statistics.median(float(r[k]) for r in rs)
    print("%-6s (%s ranks): write %.2f s, rank 0 peak memory %.0f MB (%.0f MB before the write), file %.0f bytes"
          % (mode, rs[0]["ranks"], med("write_s"), med("rss_peak_mb"), med("rss_before_mb"), med("bytes")))
PY
