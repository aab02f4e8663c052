"""Times one write of a distributed grid as .gtn under pvbatch, and rank 0's memory (bench_mpi_write.sh
runs it with N ranks).

Usage: mpirun -np N pvbatch write_timed.py PLUGIN FILE.gtn MODE OUT.gtn
  MODE parts:  GTNPartsWriter (each rank codes its share of level 0; rank 0 gathers the coded pieces)
  MODE gather: GTNWriter, level 0 alone (ParaView gathers the grid to rank 0, which codes all of it)

The ranks first read FILE.gtn (vtkGTNReader: each rank decodes its share, with GlobalPointIds), then
write it. Prints one line: `write_s=... rss_before_mb=... rss_peak_mb=... ranks=...`: rank 0's wall
clock for the write (the writer's update on every rank; rank 0, which writes the file, ends last), and
rank 0's peak resident memory before the write (after the read) and at its end."""
import resource
import sys
import time

from paraview import servermanager
from paraview.simple import LoadPlugin, OpenDataFile, SaveData

plugin, path, mode, out = sys.argv[1:5]
LoadPlugin(plugin, remote=False, ns=globals())
ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
reader = OpenDataFile(path)
reader.UpdatePipeline()
reader.GetDataInformation().GetNumberOfCells()  # every rank has read its share
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
start = time.perf_counter()
if mode == "parts":
    servermanager.writers.GTNPartsWriter(Input=reader, FileName=out).UpdatePipeline()
elif mode == "gather":
    SaveData(out, proxy=reader, Levels=0, MergeTree=0)
else:
    sys.exit("MODE is parts or gather")
elapsed = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print("write_s=%.3f rss_before_mb=%.0f rss_peak_mb=%.0f ranks=%d mode=%s" % (elapsed, before, peak, ranks, mode))
