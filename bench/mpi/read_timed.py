"""Times one read of a .gtn by vtkGTNReader under pvbatch (bench_mpi.sh runs it with 1 and N ranks).

Usage: [mpirun -np N] pvbatch read_timed.py PLUGIN FILE.gtn [THREADS]
  THREADS: the reader's Threads (the most threads each rank decodes with; default 0 = every core).

The read is the pipeline update of the reader on every rank, through the data information that
gathers every rank's counts (so rank 0's clock covers the slowest rank); loading ParaView and the plugin
and opening the file (its headers) are left out. Prints one line: `read_s=... ranks=... cells=...
points=...` (points: summed over ranks, seam points counted once per rank that holds them)."""
import sys
import time

from paraview import servermanager
from paraview.simple import LoadPlugin, OpenDataFile

plugin, path = sys.argv[1:3]
threads = int(sys.argv[3]) if len(sys.argv) > 3 else 0
LoadPlugin(plugin, remote=False, ns=globals())
ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
reader = OpenDataFile(path)
reader.Threads = threads
reader.UpdatePipelineInformation()
start = time.perf_counter()
reader.UpdatePipeline()
info = reader.GetDataInformation()
cells, points = info.GetNumberOfCells(), info.GetNumberOfPoints()
elapsed = time.perf_counter() - start
print("read_s=%.3f ranks=%d threads=%d cells=%d points=%d" % (elapsed, ranks, threads, cells, points))
