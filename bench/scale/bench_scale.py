#!/usr/bin/env python3
"""bench-scale: how convert and decode grow with the mesh, on one thread and on all of them.

For each size it generates a curvilinear grid with gtn-make-sample (a sector of a cylindrical shell
around a fin-like ridge, curved in every direction, with a smooth swirling flow: not a box), converts
it to .gtn with the default levels and merge tree (6-split), and decodes level 0 with all fields
(`gtn decode`), with --threads 1 and with every thread; --validate also times `gtn validate` of the
file. Each run is a child process whose wall time, CPU time (user + system) and peak resident set come
from the kernel (wait4's rusage).

The machine's speed wanders from one minute to the next, so the runs come in rounds (--reps, default
3): each round runs every thread count once, in turn (the order reversed every other round), and the
speed-ups are the ratios within a round, of runs made minutes apart at most. The first table gives
the median of each figure over the rounds, with [min-max] for the times; the second, per size, the
median speed-up with all threads, with [min-max] over the rounds. Every file a size's converts
write must have the same bytes, whatever the thread count or round.

Sizes are nodes per side: 64 (1.5 million tetrahedra), 128 (12.2 million), 200 (47.3 million).
The 200 size's convert takes about 185-225 s with 2 threads on a 2-core machine (330-385 s of CPU
time, and about that much wall time with 1 thread), and about 1.9 GB of memory, so each of its
rounds takes about ten minutes; --sizes chooses a subset.

    python3 bench/scale/bench_scale.py --build build --sizes 64,128 [--reps 3] [--validate]
    cmake --build build --target bench-scale      # the sizes in GTN_BENCH_SCALE_SIZES (default all three)

The table goes to standard output (Markdown); --json FILE also writes every figure.
"""
import argparse
import json
import os
import shutil
import statistics
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
    ap.add_argument("--reps", type=int, default=3, help="rounds of runs per size (default 3)")
    ap.add_argument("--validate", action="store_true", help="also time gtn validate of each file")
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
    if a.reps < 1:
        sys.exit("bench-scale: --reps: at least 1")
    all_threads = a.threads if a.threads > 0 else len(os.sched_getaffinity(0))
    thread_counts = [1] if all_threads == 1 else [1, all_threads]

    work = a.work or tempfile.mkdtemp(prefix="gtn-bench-scale-")
    os.makedirs(work, exist_ok=True)
    runs = []  # one per size, round and thread count
    try:
        for n in sizes:
            grid = os.path.join(work, "grid%d" % n)
            print("bench-scale: %d^3 nodes: generating" % n, file=sys.stderr)
            run([make_sample, grid, str(n), str(n), str(n)])
            xyz, q = os.path.join(grid, "sample.xyz"), os.path.join(grid, "sample.q")
            first_bytes = None
            same = True
            for rep in range(a.reps):
                for t in (thread_counts if rep % 2 == 0 else thread_counts[::-1]):
                    # One name for every run: the file records its name.
                    out = os.path.join(work, "grid%d.gtn" % n)
                    what = "bench-scale: %d^3 nodes, round %d of %d, %d thread(s):" % (n, rep + 1, a.reps, t)
                    print(what + " convert", file=sys.stderr)
                    cw, cc, cm, _ = run([gtn, "convert", xyz, q, "-o", out, "-q", "--threads", str(t)])
                    print(what + " decode", file=sys.stderr)
                    dw, dc, dm, text = run([gtn, "decode", out, "--json", "--threads", str(t)])
                    d = json.loads(text)
                    r = {
                        "nodes": n, "tets": d["tets"], "points": d["points"], "threads": t, "round": rep + 1,
                        "convert_wall_s": cw, "convert_cpu_s": cc, "convert_peak_rss_bytes": cm,
                        "decode_wall_s": dw, "decode_cpu_s": dc, "decode_s": d["decode_s"],
                        "decode_peak_rss_bytes": dm, "file_bytes": os.path.getsize(out),
                    }
                    if a.validate:
                        print(what + " validate", file=sys.stderr)
                        vw, vc, vm, _ = run([gtn, "validate", out, "--threads", str(t)])
                        r.update({"validate_wall_s": vw, "validate_cpu_s": vc, "validate_peak_rss_bytes": vm})
                    runs.append(r)
                    with open(out, "rb") as f:
                        data = f.read()
                    if first_bytes is None:
                        first_bytes = data
                    same = same and data == first_bytes
                    os.remove(out)
            for r in runs:
                if r["nodes"] == n:
                    r["same_bytes_all_runs"] = same
            shutil.rmtree(grid)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)

    def spread(xs, fmt):
        rng = " [" + fmt % min(xs) + "-" + fmt % max(xs) + "]" if len(xs) > 1 else ""
        return fmt % statistics.median(xs) + rng

    def of(n, t, key):
        return [r[key] for r in runs if r["nodes"] == n and r["threads"] == t]

    print("Medians over %d round(s); [min-max] where more than one." % a.reps)
    print()
    head = ("| nodes | tetrahedra | threads | convert wall s | convert CPU s | convert CPU us/tet"
            " | convert peak B/tet | decode wall s | decode s (in process) | decode ns/tet | decode peak B/tet")
    if a.validate:
        head += " | validate wall s | validate peak B/tet"
    print(head + " | file bytes | bits/tet | same bytes |")
    print("|" + "---|" * (head.count("|") + 3))
    for n in sizes:
        for t in thread_counts:
            tets = of(n, t, "tets")[0]
            fb = of(n, t, "file_bytes")[0]
            line = "| %d^3 | %d | %d | %s | %s | %.2f | %.0f | %s | %s | %.0f | %.0f" % (
                n, tets, t, spread(of(n, t, "convert_wall_s"), "%.1f"), spread(of(n, t, "convert_cpu_s"), "%.1f"),
                1e6 * statistics.median(of(n, t, "convert_cpu_s")) / tets,
                max(of(n, t, "convert_peak_rss_bytes")) / tets,
                spread(of(n, t, "decode_wall_s"), "%.2f"), spread(of(n, t, "decode_s"), "%.3f"),
                1e9 * statistics.median(of(n, t, "decode_s")) / tets,
                max(of(n, t, "decode_peak_rss_bytes")) / tets)
            if a.validate:
                line += " | %s | %.0f" % (spread(of(n, t, "validate_wall_s"), "%.1f"),
                                          max(of(n, t, "validate_peak_rss_bytes")) / tets)
            same = of(n, t, "same_bytes_all_runs")[0]
            print(line + " | %d | %.2f | %s |" % (fb, 8.0 * fb / tets, "yes" if same else "NO"))
    if len(thread_counts) > 1:
        t = thread_counts[-1]
        print()
        keys = [("convert wall", "convert_wall_s"), ("decode wall", "decode_wall_s"),
                ("decode in process", "decode_s")]
        if a.validate:
            keys.append(("validate wall", "validate_wall_s"))
        print("| nodes | " + " | ".join("%s, %d threads / 1" % (k, t) for k, _ in keys) + " |")
        print("|" + "---|" * (len(keys) + 1))
        for n in sizes:
            cells = []
            for _, key in keys:
                ratios = []
                for rep in range(1, a.reps + 1):
                    one = [r[key] for r in runs if r["nodes"] == n and r["threads"] == 1 and r["round"] == rep]
                    many = [r[key] for r in runs if r["nodes"] == n and r["threads"] == t and r["round"] == rep]
                    if one and many and many[0] > 0:
                        ratios.append(one[0] / many[0])
                cells.append(spread(ratios, "%.2f") if ratios else "-")
            print("| %d^3 | %s |" % (n, " | ".join(cells)))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"all_threads": all_threads, "reps": a.reps, "runs": runs}, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
