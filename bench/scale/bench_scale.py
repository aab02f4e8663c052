#!/usr/bin/env python3
"""bench-scale: how convert and decode grow with the mesh, on one thread and on all of them.

For each size it generates a curvilinear grid with gtn-make-sample (a sector of a cylindrical shell
around a fin-like ridge, curved in every direction, with a smooth swirling flow: not a box), converts
it to .gtn with the default levels and merge tree (6-split), and decodes level 0 with all fields
(`gtn decode`), once with --threads 1 and once with every thread. Each run is a child process whose
wall time, CPU time (user + system) and peak resident set come from the kernel (wait4's rusage).

Sizes are nodes per side: 64 (1.5 million tetrahedra), 128 (12.2 million), 200 (47.3 million).
The 200 size's convert takes about 180-190 s with 2 threads on a 2-core machine (330-350 s of CPU
time), and about 4.6 GB of memory; --sizes chooses a subset.

    python3 bench/scale/bench_scale.py --build build --sizes 64,128
    cmake --build build --target bench-scale      # the sizes in GTN_BENCH_SCALE_SIZES (default all three)

The table goes to standard output (Markdown); --json FILE also writes every figure.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


def run(cmd):
    """Runs cmd; returns (wall s, cpu s, peak RSS bytes, its standard output)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, stdout=out, stderr=err)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.monotonic() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if p.returncode != 0:
            sys.exit("bench-scale: %s failed (exit %d):\n%s" % (" ".join(cmd), p.returncode,
                                                                 err.read().decode(errors="replace")))
        return wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss * 1024, out.read().decode()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build", help="the build directory holding gtn and gtn-make-sample")
    ap.add_argument("--sizes", default="64,128,200", help="nodes per side, comma-separated (default 64,128,200)")
    ap.add_argument("--threads", type=int, default=0,
                    help="the 'all threads' count (default: every core this process may use)")
    ap.add_argument("--work", help="directory for the grids and files (default: a temporary one, removed)")
    ap.add_argument("--json", help="also write every figure to this file")
    a = ap.parse_args()

    gtn = os.path.join(a.build, "gtn")
    make_sample = os.path.join(a.build, "gtn-make-sample")
    for exe in (gtn, make_sample):
        if not os.access(exe, os.X_OK):
            sys.exit("bench-scale: %s: not found (build the gtn_cli and gtn_make_sample targets)" % exe)
    try:
        sizes = [int(s) for s in a.sizes.split(",") if s]
    except ValueError:
        sys.exit("bench-scale: --sizes: expected nodes per side, comma-separated, not '%s'" % a.sizes)
    if not sizes or any(n < 2 or n > 1024 for n in sizes):
        sys.exit("bench-scale: --sizes: each size must be from 2 to 1024 nodes per side")
    all_threads = a.threads if a.threads > 0 else len(os.sched_getaffinity(0))
    thread_counts = [1] if all_threads == 1 else [1, all_threads]

    work = a.work or tempfile.mkdtemp(prefix="gtn-bench-scale-")
    os.makedirs(work, exist_ok=True)
    rows = []
    try:
        for n in sizes:
            grid = os.path.join(work, "grid%d" % n)
            print("bench-scale: %d^3 nodes: generating" % n, file=sys.stderr)
            run([make_sample, grid, str(n), str(n), str(n)])
            xyz, q = os.path.join(grid, "sample.xyz"), os.path.join(grid, "sample.q")
            files = []
            for t in thread_counts:
                # One name in a directory per thread count: the file records its name.
                os.makedirs(os.path.join(work, "t%d" % t), exist_ok=True)
                out = os.path.join(work, "t%d" % t, "grid%d.gtn" % n)
                print("bench-scale: %d^3 nodes: convert, %d thread(s)" % (n, t), file=sys.stderr)
                cw, cc, cm, _ = run([gtn, "convert", xyz, q, "-o", out, "-q", "--threads", str(t)])
                print("bench-scale: %d^3 nodes: decode, %d thread(s)" % (n, t), file=sys.stderr)
                dw, dc, dm, text = run([gtn, "decode", out, "--json", "--threads", str(t)])
                d = json.loads(text)
                tets = d["tets"]
                rows.append({
                    "nodes": n, "tets": tets, "points": d["points"], "threads": t,
                    "convert_wall_s": cw, "convert_cpu_s": cc, "convert_peak_rss_bytes": cm,
                    "decode_wall_s": dw, "decode_cpu_s": dc, "decode_s": d["decode_s"], "decode_peak_rss_bytes": dm,
                    "file_bytes": os.path.getsize(out),
                })
                files.append(out)
            same = all(open(f, "rb").read() == open(files[0], "rb").read() for f in files[1:])
            for r in rows:
                if r["nodes"] == n:
                    r["same_bytes_all_threads"] = same
            for f in files:
                os.remove(f)
                os.rmdir(os.path.dirname(f))
            shutil.rmtree(grid)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)

    print("| nodes | tetrahedra | threads | convert wall s | convert CPU s | convert wall us/tet | convert CPU us/tet"
          " | convert peak B/tet | decode wall s | decode s (in process) | decode ns/tet | decode peak B/tet"
          " | file bytes | bits/tet | same bytes |")
    print("|" + "---|" * 15)
    for r in rows:
        t = r["tets"]
        print("| %d^3 | %d | %d | %.1f | %.1f | %.2f | %.2f | %.0f | %.2f | %.3f | %.0f | %.0f | %d | %.2f | %s |" % (
            r["nodes"], t, r["threads"], r["convert_wall_s"], r["convert_cpu_s"], 1e6 * r["convert_wall_s"] / t,
            1e6 * r["convert_cpu_s"] / t, r["convert_peak_rss_bytes"] / t, r["decode_wall_s"], r["decode_s"],
            1e9 * r["decode_s"] / t, r["decode_peak_rss_bytes"] / t, r["file_bytes"], 8.0 * r["file_bytes"] / t,
            "yes" if r["same_bytes_all_threads"] else "NO"))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"all_threads": all_threads, "rows": rows}, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
