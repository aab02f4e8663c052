#!/usr/bin/python3
"""gatun.read against the library's own decode and against meshio.read of the same mesh as a zlib .vtu.

Usage (from a build with -DGTN_BUILD_PYTHON=ON):
  PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_read.py [--gtn build/gtn]
      [--data DIR (default $GTN_DATA_DIR, else ../shared/data)] [--split 5] [--reps 7] [--level 0] [--work DIR] [--json]

The blunt fin (PLOT3D, hexahedra split in --split tetrahedra) is converted once with `gtn convert`
(default options) and exported once with `gtn export`; meshio writes that export as a zlib-compressed
.vtu. Then, --reps times, interleaved (the order rotates each round):
  gatun.read        gatun.read(path, level=L): the numpy arrays a user gets
  library decode    gatun._gatun.decode(path, L): open the file (every chunk's checksum checked) and
                    decode the level into a mesh in memory, what `gtn export` does before it writes;
                    no Python objects are made
  meshio.read       meshio.read of the zlib .vtu
  import gatun      a fresh interpreter's `import gatun` (subprocess), less a bare interpreter's
Each is timed by the wall clock and by the process's CPU time (the decode runs on one thread, so
CPU time is the figure a loaded machine disturbs least). Prints median [min, max] of each.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np

import gatun
from gatun import _gatun

ROOT = Path(__file__).resolve().parents[2]


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w, time.process_time() - c, out


def interpreter_seconds(code):
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=dict(os.environ))
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--gtn", default=str(ROOT / "build" / "gtn"))
    ap.add_argument("--data", default=os.environ.get("GTN_DATA_DIR", str(ROOT.parent / "shared" / "data")))
    ap.add_argument("--split", type=int, default=5, choices=[5, 6])
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--level", type=int, default=0)
    ap.add_argument("--work", default="/tmp/gatun-bench-read")
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    a = ap.parse_args()

    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    data = Path(a.data) / "plot3d"
    gtn_path = work / f"bluntfin-split{a.split}.gtn"
    vtu_path = work / f"bluntfin-split{a.split}-level{a.level}-zlib.vtu"
    if not gtn_path.exists():
        subprocess.run([a.gtn, "convert", data / "bluntfinxyz.bin", data / "bluntfinq.bin", "--split", str(a.split),
                        "-o", gtn_path], check=True, capture_output=True)
    if not vtu_path.exists():
        raw = work / "export.vtu"
        subprocess.run([a.gtn, "export", gtn_path, "--level", str(a.level), "-o", raw], check=True)
        meshio.write(vtu_path, meshio.read(raw), compression="zlib")
        raw.unlink()

    # The three give the same mesh (meshio holds 1-component arrays as (n, 1)).
    ours, theirs = gatun.read(gtn_path, level=a.level), meshio.read(vtu_path)
    assert np.array_equal(ours.points, theirs.points) and np.array_equal(ours.tets, theirs.cells[0].data)
    assert _gatun.decode(str(gtn_path), a.level) == (len(ours.points), len(ours.tets))
    for name, values in ours.point_data.items():
        assert np.array_equal(values.reshape(len(values), -1), theirs.point_data[name].reshape(len(values), -1))

    runs = {
        "gatun.read": lambda: gatun.read(gtn_path, level=a.level),
        "library decode": lambda: _gatun.decode(str(gtn_path), a.level),
        "meshio.read (zlib .vtu)": lambda: meshio.read(vtu_path),
    }
    wall = {k: [] for k in runs}
    cpu = {k: [] for k in runs}
    names = list(runs)
    for fn in runs.values():  # warm: page cache, allocator, lazy imports
        fn()
    for r in range(a.reps):
        for k in names[r % len(names):] + names[: r % len(names)]:
            w, c, _ = timed(runs[k])
            wall[k].append(w)
            cpu[k].append(c)
    imports = []
    for _ in range(a.reps):
        imports.append(interpreter_seconds("import gatun") - interpreter_seconds("pass"))

    def summary(xs):
        return {"median": statistics.median(xs), "min": min(xs), "max": max(xs)}

    out = {
        "file": str(gtn_path), "bytes": gtn_path.stat().st_size, "vtu_bytes": vtu_path.stat().st_size,
        "level": a.level, "points": len(ours.points), "tets": len(ours.tets), "reps": a.reps,
        "wall": {k: summary(v) for k, v in wall.items()},
        "cpu": {k: summary(v) for k, v in cpu.items()},
        "import_gatun_wall": summary(imports),
    }
    if a.json:
        print(json.dumps(out, indent=2))
        return
    print(f"{gtn_path.name}: level {a.level}, {out['points']} points, {out['tets']} tetrahedra; "
          f".gtn {out['bytes']} bytes, zlib .vtu {out['vtu_bytes']} bytes; {a.reps} interleaved runs")
    print(f"  {'':26}{'wall s: median [min, max]':32}{'cpu s: median [min, max]'}")
    for k in names:
        w, c = out["wall"][k], out["cpu"][k]
        print(f"  {k:26}{w['median']:.3f} [{w['min']:.3f}, {w['max']:.3f}]{'':10}"
              f"{c['median']:.3f} [{c['min']:.3f}, {c['max']:.3f}]")
    i = out["import_gatun_wall"]
    print(f"  {'import gatun':26}{i['median']:.3f} [{i['min']:.3f}, {i['max']:.3f}]")
    for what in ("wall", "cpu"):
        m = {k: out[what][k]["median"] for k in names}
        print(f"  {what}: gatun.read / library decode {m['gatun.read'] / m['library decode']:.3f}, "
              f"gatun.read / meshio.read {m['gatun.read'] / m['meshio.read (zlib .vtu)']:.3f}")


if __name__ == "__main__":
    main()
