"""Helpers shared by the ParaView plugin's tests (run under pvbatch): loading the plugin, running the
gtn CLI, the sorted-tetrahedra checksum and rendering with `gtn render`'s camera and transfer function."""
import hashlib
import json
import subprocess
import sys

from paraview import servermanager
from paraview.simple import (ColorBy, CreateView, Delete, GetColorTransferFunction, GetOpacityTransferFunction,
                             LoadPlugin, Render, SaveScreenshot, Show)
from vtkmodules.util.numpy_support import vtk_to_numpy
import numpy


def fail(message):
    print("FAIL: " + message, file=sys.stderr)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)
    print("ok: " + message)


def load_plugin(path):
    LoadPlugin(path, remote=False, ns=globals())


def gtn(binary, *args):
    """Runs the gtn CLI; returns its standard output (fails the test on a non-zero exit)."""
    p = subprocess.run([binary, *args], capture_output=True, text=True)
    if p.returncode != 0:
        fail("gtn %s: exit %d: %s" % (" ".join(args), p.returncode, p.stderr.strip()))
    return p.stdout


def tets_of(grid, point_ids=None):
    """The grid's tetrahedra as an (n, 4) array of point numbers: `point_ids` maps the grid's points to
    the file's (GlobalPointIds of a piece), identity otherwise."""
    cells = grid.GetCells()
    conn = vtk_to_numpy(cells.GetConnectivityArray()).astype(numpy.int64)
    offsets = vtk_to_numpy(cells.GetOffsetsArray())
    if len(offsets) > 1 and not numpy.all(numpy.diff(offsets) == 4):
        fail("cells that are not tetrahedra")
    tets = conn.reshape(-1, 4)
    if point_ids is not None:
        tets = point_ids[tets]
    return tets


def checksum(tets):
    """SHA-256 of the tetrahedra (vertex order kept) sorted lexicographically, as little-endian int64."""
    order = numpy.lexsort(tets.T[::-1])
    return hashlib.sha256(numpy.ascontiguousarray(tets[order]).astype("<i8").tobytes()).hexdigest()


def coordinate_checksum(*grids):
    """SHA-256 of the tetrahedra of `grids` as their corners' coordinates (each tetrahedron's corners
    sorted, then the tetrahedra sorted): the same for any numbering of the points and tetrahedra, and
    any split of them into grids."""
    corners = numpy.concatenate([vtk_to_numpy(g.GetPoints().GetData()).astype("<f8")[tets_of(g)] for g in grids
                                 if g.GetNumberOfCells() > 0])  # (n, 4, 3)
    keys = numpy.ascontiguousarray(corners).view([("x", "<f8"), ("y", "<f8"), ("z", "<f8")]).reshape(-1, 4)
    keys = numpy.sort(keys, axis=1)
    flat = numpy.ascontiguousarray(keys).view("<f8").reshape(len(keys), 12)
    order = numpy.lexsort(flat.T[::-1])
    return hashlib.sha256(numpy.ascontiguousarray(flat[order]).tobytes()).hexdigest()


def render_like_gtn(source, view_json, png, mapper="Bunyk ray cast"):
    """Volume-renders `source` with the camera and transfer function `gtn render --dump-view` wrote,
    with ParaView's `mapper` (default the Bunyk ray caster, as bench/render/vtk_compare.py), into `png`."""
    with open(view_json) as f:
        v = json.load(f)
    cam, tf = v["camera"], v["transfer"]
    view = CreateView("RenderView")
    view.ViewSize = [cam["width"], cam["height"]]
    view.OrientationAxesVisibility = 0
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = v.get("background", [0, 0, 0])
    display = Show(source, view)
    display.SetRepresentationType("Volume")
    display.SelectMapper = mapper
    ColorBy(display, ("POINTS", tf["field"]))
    lut = GetColorTransferFunction(tf["field"])
    lut.AutomaticRescaleRangeMode = "Never"
    lut.ColorSpace = "RGB"
    lut.Discretize = 0
    lut.RGBPoints = [x for p in tf["points"] for x in (p["value"], *p["rgb"])]
    pwf = GetOpacityTransferFunction(tf["field"])
    pwf.Points = [x for p in tf["points"] for x in (p["value"], p["opacity"], 0.5, 0.0)]
    display.ScalarOpacityFunction = pwf
    display.ScalarOpacityUnitDistance = tf["opacity_unit_distance"]
    view.CameraPosition = cam["position"]
    view.CameraFocalPoint = cam["focal_point"]
    view.CameraViewUp = cam["view_up"]
    if cam["projection"] == "ortho":
        view.CameraParallelProjection = 1
        view.CameraParallelScale = cam["parallel_scale"]
    else:
        view.CameraParallelProjection = 0
        view.CameraViewAngle = cam["view_angle"]
    Render(view)
    if cam.get("pixel_centres", True):
        # VTK casts the ray of a pixel through its lower-left corner, gtn render through its centre.
        view.GetActiveCamera().SetWindowCenter(1.0 / cam["width"], 1.0 / cam["height"])
    Render(view)
    SaveScreenshot(png, view, ImageResolution=[cam["width"], cam["height"]])
    # The view goes before the process ends: a render window left to the interpreter's teardown
    # outlives its X connection (GLXBadContext under xvfb-run).
    Delete(view)
