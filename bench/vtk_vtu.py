#!/usr/bin/python3
"""VTK's side of bench-compression and bench-load: .vtu files written and read by VTK itself.

Usage (VTK's Python modules: Debian's python3-paraview, or ParaView's pvpython):
  vtk_vtu.py write MESH.vtu PREFIX
      reads MESH.vtu (the mesh as `gtn export` writes it: points, tetrahedra, all point and cell
      fields) and writes it again with vtkXMLUnstructuredGridWriter, appended binary data (not
      base64), VTK's defaults otherwise (compression level 5, UInt64 headers, Int64 connectivity):
      PREFIX.zlib.vtu, PREFIX.lz4.vtu, PREFIX.lzma.vtu (compressed) and PREFIX.raw.vtu (uncompressed).
      Prints one line per file: "KIND BYTES POINTS CELLS".
  vtk_vtu.py serve
      reads one .vtu path per line on standard input and answers, per line, "WALL_S CPU_S POINTS CELLS
      ARRAYS": the wall-clock and process CPU seconds of a new vtkXMLUnstructuredGridReader's
      Update() alone (every point and cell array read), on a warm process. "error MESSAGE" when the
      file cannot be read. Ends at end of input.
Exit status 0, 1 on an unreadable or empty mesh, 2 on a usage error, 3 when VTK cannot be imported.
"""
import os
import sys
import time

try:
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter
except ImportError:
    try:
        from vtk import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter
    except ImportError as e:
        print(f"vtk_vtu: VTK's Python modules are not available: {e}", file=sys.stderr)
        sys.exit(3)

KINDS = ("zlib", "lz4", "lzma", "raw")


def read(path):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    reader.Update()
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    grid = reader.GetOutput()
    if reader.GetErrorCode() != 0 or grid is None or grid.GetNumberOfCells() == 0:
        raise RuntimeError(f"{path}: VTK read no cells")
    arrays = grid.GetPointData().GetNumberOfArrays() + grid.GetCellData().GetNumberOfArrays()
    return grid, wall, cpu, arrays


def write(src, prefix):
    grid, _, _, _ = read(src)
    for kind in KINDS:
        path = f"{prefix}.{kind}.vtu"
        w = vtkXMLUnstructuredGridWriter()
        w.SetFileName(path)
        w.SetInputData(grid)
        w.SetDataModeToAppended()
        w.EncodeAppendedDataOff()
        if kind == "zlib":
            w.SetCompressorTypeToZLib()
        elif kind == "lz4":
            w.SetCompressorTypeToLZ4()
        elif kind == "lzma":
            w.SetCompressorTypeToLZMA()
        else:
            w.SetCompressorTypeToNone()
        if w.Write() != 1:
            raise RuntimeError(f"{path}: VTK could not write it")
        print(kind, os.path.getsize(path), grid.GetNumberOfPoints(), grid.GetNumberOfCells(), flush=True)


def serve():
    # The process's own streams: pvpython replaces sys.stdin and sys.stdout with its console's.
    stdin, stdout = sys.__stdin__, sys.__stdout__
    for line in iter(stdin.readline, ""):
        path = line.rstrip("\n")
        if not path:
            continue
        try:
            grid, wall, cpu, arrays = read(path)
            answer = f"{wall:.6f} {cpu:.6f} {grid.GetNumberOfPoints()} {grid.GetNumberOfCells()} {arrays}"
        except Exception as e:  # the bench reports the message and goes on
            answer = f"error {e}"
        stdout.write(answer + "\n")
        stdout.flush()


def main(argv):
    if len(argv) == 4 and argv[1] == "write":
        try:
            write(argv[2], argv[3])
        except RuntimeError as e:
            print(f"vtk_vtu: {e}", file=sys.stderr)
            return 1
        return 0
    if len(argv) == 2 and argv[1] == "serve":
        serve()
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
