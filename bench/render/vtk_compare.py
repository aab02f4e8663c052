#!/usr/bin/python3
"""Render a mesh with VTK's vtkUnstructuredGridVolumeRayCastMapper exactly as `gtn render` did.

Usage (headless):
  xvfb-run -a /usr/bin/python3 bench/render/vtk_compare.py MESH.vtu VIEW.json OUT.png [--frames N]
      [--integrator NAME] [--ours OURS.png [--gtn build/gtn]] [--json]

MESH.vtu is the same mesh `gtn render` rendered (`gtn export x.gtn -o x.vtu`), VIEW.json the camera and
transfer function that `gtn render ... --dump-view VIEW.json` wrote: nothing here re-derives our
defaults. The script loads the mesh once, renders one warm-up frame (VTK builds its per-mesh
structures there), then N more frames of the already loaded mesh, writes the last frame as a PNG and
prints the time of the first frame and the mean time per frame of the others (seconds); with --ours,
also the RMSE between VTK's image and ours (`gtn compare`).

Conventions matched (see render/README.md, "Comparing with VTK"):
* camera: position, focal point, view up, parallel projection with the same parallel scale (or the
  same vertical view angle), image size, black background;
* transfer function: the same colour points (vtkColorTransferFunction, RGB space, no clamping
  surprises: the end points are at the range ends) and opacity points (vtkPiecewiseFunction) at the
  same scalar values, and the same scalar opacity unit distance;
* rays through every pixel (ImageSampleDistance 1, no automatic adjustment), linear interpolation;
  VTK casts rays through pixel corners, ours through pixel centres: the window is shifted by half a
  pixel (vtkCamera::SetWindowCenter) so that the rays coincide.
VTK's unstructured-grid integrators take the attenuation as opacity / unit distance, linear in the
scalar between control points; `gtn render` uses the same convention (render/transfer_function.h).
Needs VTK's Python modules (Debian's python3-paraview) (use /usr/bin/python3, not a virtual environment's).
"""
import argparse
import json
import subprocess
import sys
import time

import vtk


INTEGRATORS = {
    "default": None,  # the mapper's own choice: pre-integration tables for point scalars
    "preintegration": "vtkUnstructuredGridPreIntegration",
    "partial": "vtkUnstructuredGridPartialPreIntegration",
    "linear": "vtkUnstructuredGridLinearRayIntegrator",
    "homogeneous": "vtkUnstructuredGridHomogeneousRayIntegrator",
}


def build_pipeline(mesh_path, view, field, integrator):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(mesh_path)
    reader.Update()
    grid = reader.GetOutput()
    if grid.GetNumberOfCells() == 0:
        sys.exit(f"vtk_compare: {mesh_path}: no cells")
    name = field.split(":")[0]
    pd = grid.GetPointData()
    if name:
        array = pd.GetArray(name)
        if array is None:
            sys.exit(f"vtk_compare: {mesh_path}: no point field '{name}'")
    else:
        array = pd.GetArray(0)
    if array.GetNumberOfComponents() != 1:
        # VTK's volume mappers render one component: extract the one (or the magnitude) we rendered.
        comp = field.split(":")[1] if ":" in field else "0"
        calc = vtk.vtkArrayCalculator()
        calc.SetInputData(grid)
        calc.SetAttributeTypeToPointData()
        calc.AddVectorArrayName(array.GetName())
        if comp == "mag":
            calc.SetFunction(f"mag({array.GetName()})")
        else:
            calc.AddScalarVariable("c", array.GetName(), int(comp))
            calc.SetFunction("c")
        calc.SetResultArrayName("gtn_scalar")
        calc.Update()
        grid = calc.GetOutput()
        grid.GetPointData().SetActiveScalars("gtn_scalar")
    else:
        pd.SetActiveScalars(array.GetName())

    tf = view["transfer"]
    colour = vtk.vtkColorTransferFunction()
    opacity = vtk.vtkPiecewiseFunction()
    for p in tf["points"]:
        colour.AddRGBPoint(p["value"], *p["rgb"])
        opacity.AddPoint(p["value"], p["opacity"])
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(tf["opacity_unit_distance"])
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()

    mapper = vtk.vtkUnstructuredGridVolumeRayCastMapper()
    mapper.SetInputData(grid)
    mapper.SetScalarModeToUsePointData()
    mapper.AutoAdjustSampleDistancesOff()
    mapper.SetImageSampleDistance(1.0)
    if INTEGRATORS[integrator]:
        mapper.SetRayIntegrator(getattr(vtk, INTEGRATORS[integrator])())
    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    cam_view = view["camera"]
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(*view.get("background", [0, 0, 0]))
    renderer.AddVolume(volume)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(*cam_view["position"])
    camera.SetFocalPoint(*cam_view["focal_point"])
    camera.SetViewUp(*cam_view["view_up"])
    if cam_view["projection"] == "ortho":
        camera.ParallelProjectionOn()
        camera.SetParallelScale(cam_view["parallel_scale"])
    else:
        camera.ParallelProjectionOff()
        camera.SetViewAngle(cam_view["view_angle"])
    if cam_view.get("pixel_centres", True):
        # VTK's Bunyk ray caster casts the ray of pixel (x, y) (y from the bottom) through normalized
        # device coordinates (2x/W - 1, 2y/H - 1): the pixel's lower-left corner. Ours go through pixel
        # centres. Shifting the window by half a pixel puts VTK's rays where ours are.
        camera.SetWindowCenter(1.0 / cam_view["width"], 1.0 / cam_view["height"])
    renderer.ResetCameraClippingRange()

    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.AddRenderer(renderer)
    window.SetSize(cam_view["width"], cam_view["height"])
    return grid, window, renderer


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh")
    ap.add_argument("view")
    ap.add_argument("output")
    ap.add_argument("--frames", type=int, default=5, help="frames timed after the first (default 5)")
    ap.add_argument("--integrator", choices=sorted(INTEGRATORS), default="default",
                    help="VTK's ray integrator (default: the mapper's own, pre-integration)")
    ap.add_argument("--ours", help="our image of the same view: report the RMSE against it")
    ap.add_argument("--gtn", default="build/gtn", help="the gtn binary used for `gtn compare` (default build/gtn)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    with open(args.view) as f:
        view = json.load(f)
    t0 = time.perf_counter()
    grid, window, renderer = build_pipeline(args.mesh, view, view["transfer"].get("field", ""), args.integrator)
    load_s = time.perf_counter() - t0

    t0 = time.perf_counter()
    window.Render()
    first_s = time.perf_counter() - t0
    times = []
    for _ in range(max(1, args.frames)):
        # Mark the volume modified in the renderer's eyes only: a new frame, same mesh and camera.
        renderer.GetActiveCamera().Modified()
        t0 = time.perf_counter()
        window.Render()
        times.append(time.perf_counter() - t0)

    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(args.output)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()

    result = {
        "vtk_version": vtk.vtkVersion.GetVTKVersion(),
        "tets": grid.GetNumberOfCells(),
        "integrator": args.integrator,
        "load_s": load_s,
        "first_frame_s": first_s,
        "frames": len(times),
        "mean_frame_s": sum(times) / len(times),
        "min_frame_s": min(times),
        "output": args.output,
    }
    if args.ours:
        cmp = subprocess.run([args.gtn, "compare", args.ours, args.output, "--json"], check=True,
                             capture_output=True, text=True)
        diff = json.loads(cmp.stdout)
        result.update({"ours": args.ours, "rmse": diff["rmse"], "psnr": diff["psnr"],
                       "max_difference": diff["max_difference"], "pixels_compared": diff["pixels_compared"]})
    if args.json:
        print(json.dumps(result))
    else:
        for k, v in result.items():
            print(f"{k:15} {v}")


if __name__ == "__main__":
    main()
