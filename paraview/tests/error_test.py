"""vtkGTNReader's errors carry the library's message (ctest paraview_errors matches them in the output):
a file that is not .gtn, and a .gtn cut short.

Usage: pvbatch error_test.py GTN PLUGIN TMP_DIR"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gtn_pv  # noqa: E402
from gtn_pv import gtn  # noqa: E402
from paraview import servermanager  # noqa: E402

binary, plugin, tmp = sys.argv[1:4]
os.makedirs(tmp, exist_ok=True)
gtn_pv.load_plugin(plugin)
# A small mesh of the project's own: a cube of 6 tetrahedra with a point field.
vtk = os.path.join(tmp, "cube.vtk")
with open(vtk, "w") as f:
    f.write("# vtk DataFile Version 3.0\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 8 double\n"
            "0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1\nCELLS 6 30\n"
            "4 0 1 2 6\n4 0 2 3 6\n4 0 3 7 6\n4 0 7 4 6\n4 0 4 5 6\n4 0 5 1 6\n"
            "CELL_TYPES 6\n10 10 10 10 10 10\nPOINT_DATA 8\nSCALARS t float 1\nLOOKUP_TABLE default\n"
            "0 1 2 3 4 5 6 7\n")
good = os.path.join(tmp, "cube.gtn")
gtn(binary, "convert", vtk, "-o", good, "--levels", "0")
with open(good, "rb") as f:
    data = f.read()
bad_magic = os.path.join(tmp, "notgtn.gtn")
with open(bad_magic, "wb") as f:
    f.write(b"solid cube\n" + data[11:])
truncated = os.path.join(tmp, "truncated.gtn")
with open(truncated, "wb") as f:
    f.write(data[: len(data) // 2])
for path in (bad_magic, truncated):
    reader = servermanager.sources.GatunGTNreader(FileName=path)
    reader.UpdatePipeline()
    print("read %s: %d cells" % (os.path.basename(path), reader.GetDataInformation().GetNumberOfCells()))
reader = servermanager.sources.GatunGTNreader(FileName=good)
reader.UpdatePipeline()
print("read cube.gtn: %d cells" % reader.GetDataInformation().GetNumberOfCells())
