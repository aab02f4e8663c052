"""The ParaView plugin, headless under pvbatch: File > Open of a .gtn (counts of a level and of a ratio,
array selection, stored precision), a volume rendering compared with `gtn render`'s image, and
File > Save Data back to .gtn.

Usage: xvfb-run -a pvbatch plugin_test.py GTN PLUGIN DATA_DIR TMP_DIR (GTN_DATA_DIR overrides DATA_DIR)"""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gtn_pv  # noqa: E402
from gtn_pv import check, gtn  # noqa: E402
from paraview import servermanager  # noqa: E402
from paraview.simple import OpenDataFile, SaveData  # noqa: E402

binary, plugin, data, tmp = sys.argv[1:5]
data = os.environ.get("GTN_DATA_DIR", data)
if not os.path.isfile(os.path.join(data, "plot3d/bluntfinxyz.bin")):
    print("skipped: no %s/plot3d/bluntfinxyz.bin" % data)
    sys.exit(77)
os.makedirs(tmp, exist_ok=True)
gtn_pv.load_plugin(plugin)
src = os.path.join(tmp, "bluntfin.gtn")
gtn(binary, "convert", os.path.join(data, "plot3d/bluntfinxyz.bin"), os.path.join(data, "plot3d/bluntfinq.bin"), "-o", src)
info = json.loads(gtn(binary, "info", "--json", src))

# File > Open picks the plugin's reader for .gtn.
reader = OpenDataFile(src)
check(reader is not None and reader.GetXMLName() == "GTNReader", "OpenDataFile picks the GTN reader")
grid = servermanager.Fetch(reader)
check(grid.GetNumberOfPoints() == info["points"] and grid.GetNumberOfCells() == info["tets"],
      "level 0: %d points, %d tets as gtn info" % (grid.GetNumberOfPoints(), grid.GetNumberOfCells()))
check(all(grid.GetCellType(i) == 10 for i in range(0, grid.GetNumberOfCells(), 997)), "cells are VTK_TETRA")
check(grid.GetPoints().GetData().IsA("vtkFloatArray"), "float32 coordinates stay float")
names = sorted(grid.GetPointData().GetArrayName(i) for i in range(grid.GetPointData().GetNumberOfArrays()))
check(names == sorted(f["name"] for f in info["fields"] if f["location"] == "point"), "point arrays %s" % names)
check(grid.GetPointData().GetArray("density").IsA("vtkFloatArray"), "float32 field stays vtkFloatArray")
check(grid.GetPointData().GetArray("momentum").GetNumberOfComponents() == 3, "momentum has 3 components")

# Ratio 0.5: the counts of `gtn export --ratio 0.5`.
vtu = os.path.join(tmp, "ratio.vtu")
gtn(binary, "export", src, "--ratio", "0.5", "-o", vtu)
ref = json.loads(gtn(binary, "info", "--json", vtu))
reader.Ratio = 0.5
grid = servermanager.Fetch(reader)
check((grid.GetNumberOfPoints(), grid.GetNumberOfCells()) == (ref["points"], ref["tets"]),
      "ratio 0.5: %d points, %d tets as gtn export --ratio 0.5" % (grid.GetNumberOfPoints(), grid.GetNumberOfCells()))
reader.Ratio = 0
reader.Level = len(info["levels"]) - 1
grid = servermanager.Fetch(reader)
check(grid.GetNumberOfCells() == info["levels"][-1]["tets"], "coarsest level: %d tets" % grid.GetNumberOfCells())
reader.Level = 0

# Array selection: only the chosen arrays are decoded.
reader.PointArrays = ["density"]
grid = servermanager.Fetch(reader)
check(grid.GetPointData().GetNumberOfArrays() == 1 and grid.GetPointData().GetArray("density") is not None,
      "point array selection keeps density only")
reader.PointArrays = [n for n in names]

# Rendering: the same camera and transfer function as gtn render.
ours, view, pv_png = (os.path.join(tmp, n) for n in ("gtn.png", "view.json", "paraview.png"))
gtn(binary, "render", src, "-o", ours, "--dump-view", view)
gtn_pv.render_like_gtn(reader, view, pv_png)
cmp = json.loads(gtn(binary, "compare", "--json", ours, pv_png))
print("compare:", cmp)
check(cmp["rmse"] < 3.0, "ParaView's image equals gtn render's up to RMSE %.3f < 3" % cmp["rmse"])

# File > Save Data writes .gtn: level 0 equals the source up to renumbering.
out = os.path.join(tmp, "saved.gtn")
SaveData(out, proxy=reader)
gtn(binary, "validate", out, "--against", src)
check(True, "saved .gtn validates against the source")
saved = json.loads(gtn(binary, "info", "--json", out))
check((saved["points"], saved["tets"]) == (info["points"], info["tets"]), "saved .gtn has the source's counts")

# A mesh with errors of its own (two overlapping tetrahedra) is refused, nothing written, unless
# KeepInvalid stores it as it is (then `gtn validate` reports it).
with open(os.path.join(tmp, "overlap.node"), "w") as f:
    f.write("5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.1 0.1 0.1\n")
with open(os.path.join(tmp, "overlap.ele"), "w") as f:
    f.write("2 4 0\n1 1 2 3 4\n2 1 2 3 5\n")
overlap_vtu = os.path.join(tmp, "overlap.vtu")
gtn(binary, "convert", os.path.join(tmp, "overlap.node"), "-o", overlap_vtu)
bad = OpenDataFile(overlap_vtu)
refused = os.path.join(tmp, "refused.gtn")
SaveData(refused, proxy=bad)
check(not os.path.exists(refused), "the writer refuses a mesh with errors of its own")
kept = os.path.join(tmp, "kept.gtn")
SaveData(kept, proxy=bad, KeepInvalid=1)
check(os.path.exists(kept), "KeepInvalid writes it")
check(subprocess.run([binary, "validate", kept], capture_output=True).returncode == 1,
      "gtn validate reports the kept mesh's errors")
print("PASS")
