"""The plugin under MPI: `mpirun -np N pvbatch mpi_test.py ...` reads one .gtn, each rank the tetrahedra
of its slab; the union of the ranks' pieces must equal the serial read (counts and the checksum of the
sorted tetrahedra), the image ParaView composites must equal the serial one, and File > Save Data must\nwrite one .gtn equal to the source.

Usage: pvbatch mpi_test.py GTN PLUGIN SOURCE.gtn TMP_DIR --serial OUT.json   (the serial reference)
       mpirun -np N pvbatch mpi_test.py GTN PLUGIN SOURCE.gtn TMP_DIR --against OUT.json"""
import json
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gtn_pv  # noqa: E402
from gtn_pv import check, gtn  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import OpenDataFile, SaveData  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402

binary, plugin, src, tmp, mode, ref_json = sys.argv[1:7]
os.makedirs(tmp, exist_ok=True)
gtn_pv.load_plugin(plugin)
ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
reader = OpenDataFile(src)

if mode == "--serial":
    check(ranks == 1, "serial reference on one rank")
    grid = servermanager.Fetch(reader)
    tets = gtn_pv.tets_of(grid)
    # Projected tetrahedra: the volume mapper ParaView composites across ranks in depth order.
    gtn(binary, "render", src, "-o", os.path.join(tmp, "gtn.png"), "--dump-view", os.path.join(tmp, "view.json"))
    gtn_pv.render_like_gtn(reader, os.path.join(tmp, "view.json"), os.path.join(tmp, "paraview-serial.png"),
                           "Projected tetra")
    with open(ref_json, "w") as f:
        json.dump({"points": grid.GetNumberOfPoints(), "tets": len(tets), "checksum": gtn_pv.checksum(tets)}, f)
    print("PASS")
    sys.exit(0)

with open(ref_json) as f:
    ref = json.load(f)
check(ranks > 1, "%d ranks" % ranks)
# Each rank's own piece, fetched one rank at a time (Fetch(proxy, rank)).
reader.UpdatePipeline()
pieces = [servermanager.Fetch(reader, rank) for rank in range(ranks)]
check(all(p.GetPointData().GetArray("GlobalPointIds") is not None and p.GetCellData().GetArray("GlobalCellIds")
          is not None for p in pieces), "pieces carry global ids")
per_rank = [p.GetNumberOfCells() for p in pieces]
print("tetrahedra per rank:", per_rank)
check(all(0 < n < ref["tets"] for n in per_rank), "each rank holds a share, not the whole mesh")
point_ids = numpy.concatenate([vtk_to_numpy(p.GetPointData().GetArray("GlobalPointIds")) for p in pieces])
tets = numpy.concatenate([gtn_pv.tets_of(p, vtk_to_numpy(p.GetPointData().GetArray("GlobalPointIds"))) for p in pieces])
cell_ids = numpy.sort(numpy.concatenate([vtk_to_numpy(p.GetCellData().GetArray("GlobalCellIds")) for p in pieces]))
check(len(tets) == ref["tets"], "union: %d tets as the serial read" % len(tets))
check(len(numpy.unique(point_ids)) == ref["points"], "union: %d distinct points as the serial read" % ref["points"])
check(gtn_pv.checksum(tets) == ref["checksum"], "union: sorted-tet checksum equals the serial read's")
check(numpy.array_equal(cell_ids, numpy.arange(ref["tets"])), "every tetrahedron in exactly one piece")

# The image ParaView composites from the ranks' pieces equals the serial one.
mpi_png = os.path.join(tmp, "paraview-mpi.png")
gtn_pv.render_like_gtn(reader, os.path.join(tmp, "view.json"), mpi_png, "Projected tetra")
cmp = json.loads(gtn(binary, "compare", "--json", os.path.join(tmp, "paraview-serial.png"), mpi_png))
print("compare:", cmp)
check(cmp["rmse"] < 1.5, "composited image equals the serial image up to RMSE %.3f < 1.5" % cmp["rmse"])

# Save Data under MPI: the pieces are gathered to rank 0, which writes one .gtn.
out = os.path.join(tmp, "saved-mpi.gtn")
SaveData(out, proxy=reader)
gtn(binary, "validate", out, "--against", src)
saved = json.loads(gtn(binary, "info", "--json", out))
check((saved["points"], saved["tets"]) == (ref["points"], ref["tets"]), "saved .gtn: one file with the source's mesh")
print("PASS")
