#!/bin/sh
# ParaView's MPI reading one .gtn: `mpirun -np 1` against `-np N pvbatch`, each rank of N decoding only
# its run of the file's pieces (vtkGTNReader). The grid is the project's sample shape at SIZE^3 points
# (gtn-make-sample; 128 gives 127^3 x 6 = 12.3 million tetrahedra), converted with `gtn convert --levels 0
# --no-merge-tree --piece-tets 524288` (level 0 alone, no ranking; pieces of at most 2^19 tetrahedra). A rank
# decodes its pieces in parallel too (TBB), so each round runs, in turn (interleaved, so that whatever
# else the machine does weighs on all of them):
#   1 rank, every core (the reader's default, Threads 0)      N ranks, every core each (Threads 0)
#   1 rank, 1 thread (Threads 1)                              N ranks, cores / N threads each
#   N ranks, 1 thread each (when cores / N is not 1)
# The time is the read alone (read_timed.py: the reader's pipeline update on every rank, without
# starting ParaView), and also the whole pvbatch run. Prints each run, the medians and the speed-ups:
# N ranks against 1 rank with every core, and N ranks of 1 thread against 1 rank of 1 thread.
#
# Usage: bench/mpi/bench_mpi.sh [SIZE] [RANKS] [ROUNDS] [BUILD_DIR]
#   (defaults: 128, 2, 3, build). Needs pvbatch, mpirun and the plugin built (GatunPlugin).
#   The converted file stays in $BENCH_MPI_DIR when that is set (a later run with the same SIZE reuses it).
#   Timings are wall-clock on whatever else the machine is doing.
set -eu
size=${1:-128}
ranks=${2:-2}
rounds=${3:-3}
build=${4:-build}
here=$(cd "$(dirname "$0")" && pwd)
name=bench_mpi
. "$here/grid_file.sh"
python3 - "$gtn" "$file" <<'PY'
import json, subprocess, sys
j = json.loads(subprocess.run([sys.argv[1], "info", "--json", sys.argv[2]], capture_output=True, check=True, text=True).stdout)
l = j["levels"][0]
print("file: %d tetrahedra, %d points, %d pieces, %d bytes" % (l["tets"], l["points"], l["piece_count"], j["bytes"]))
PY

cores=$(nproc)
split=$((cores / ranks))
[ "$split" -ge 1 ] || split=1
# run NP THREADS: one timed read; prints "read_s whole_s", and the read's line to stderr.
run() {
  t0=$(date +%s.%N)
  line=$(mpirun --allow-run-as-root --oversubscribe -np "$1" pvbatch "$here/read_timed.py" "$plugin" "$file" "$2" \
         2>/dev/null | grep '^read_s=')
  t1=$(date +%s.%N)
  echo "  np $1: $line whole_s=$(echo "$t1 - $t0" | bc)" >&2
  echo "$(echo "$line" | sed 's/^read_s=\([0-9.]*\).*/\1/') $(echo "$t1 - $t0" | bc)"
}
configs="1:0 1:1 $ranks:0 $ranks:$split"
[ "$split" -eq 1 ] || configs="$configs $ranks:1"
results=""
i=1
while [ $i -le "$rounds" ]; do
  echo "round $i"
  for c in $configs; do
    results="$results$c $(run "${c%:*}" "${c#*:}")
"
  done
  i=$((i + 1))
done
python3 - "$ranks" "$split" "$cores" "$results" <<'PY'
import statistics, sys
ranks, split, cores = (int(v) for v in sys.argv[1:4])
runs = {}
for line in sys.argv[4].strip().splitlines():
    config, read_s, whole_s = line.split()
    np_, threads = (int(v) for v in config.split(":"))
    runs.setdefault((np_, threads), []).append((float(read_s), float(whole_s)))
med = {c: tuple(statistics.median(r[k] for r in rs) for k in (0, 1)) for c, rs in runs.items()}
name = lambda np_, t: "%d rank(s) x %s" % (np_, "every core" if t == 0 else "%d thread(s)" % t)
print("medians over %d cores (read s, whole pvbatch run s):" % cores)
for c in sorted(med):
    print("  %-28s %7.2f %7.2f" % (name(*c), *med[c]))
for k, what in ((0, "read"), (1, "whole run")):
    print("speed-up of the %s: %d ranks x every core %.2f, %d ranks x %d thread(s) %.2f (both against 1 rank x every "
          "core); %d ranks x 1 thread against 1 rank x 1 thread %.2f"
          % (what, ranks, med[(1, 0)][k] / med[(ranks, 0)][k], ranks, split, med[(1, 0)][k] / med[(ranks, split)][k],
             ranks, med[(1, 1)][k] / med[(ranks, 1)][k]))
PY
