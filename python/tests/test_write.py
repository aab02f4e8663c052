"""gatun.write against `gtn convert`: the same encoder, levels, verification and atomic output."""

import os
import threading
import time
import warnings

import numpy as np
import pytest

import gatun


def sections(info):
    # The header holds the provenance (command line), which differs between the two writers.
    return {s["name"]: s["bytes"] for s in info["sections"] if s["name"] != "header"}


@pytest.mark.parametrize("name", ["bunny", "bluntfin"])
def test_write_equals_convert(gtn, converted, tmp_path, name):
    # The same mesh in the same order: `gtn convert` reads a .gtn's level 0, gatun reads it too.
    cli = tmp_path / "cli.gtn"
    gtn.run("convert", converted[name], "-o", cli)
    mesh = gatun.read(converted[name])
    py = tmp_path / "py.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zero-volume tetrahedra of the blunt fin, as gtn says
        gatun.write(py, mesh.points, mesh.tets, point_data=mesh.point_data, cell_data=mesh.cell_data,
                    metadata=mesh.metadata)
    a, b = gatun.info(cli), gatun.info(py)
    assert sections(a) == sections(b)
    assert [(l["points"], l["tets"], l["merges"], l["ratio"], l["bytes"]) for l in a["levels"]] == [
        (l["points"], l["tets"], l["merges"], l["ratio"], l["bytes"]) for l in b["levels"]
    ]
    assert b["provenance"]["command_line"] == f"gatun.write({py})"
    # Every chunk after the header is the same bytes.
    ca, cb = cli.read_bytes(), py.read_bytes()
    ha = sum(s["bytes"] for s in a["sections"] if s["name"] in ("prefix", "header"))
    hb = sum(s["bytes"] for s in b["sections"] if s["name"] in ("prefix", "header"))
    level_a = ca[ha:ha + sum(l["bytes"] for l in a["levels"])]
    level_b = cb[hb:hb + sum(l["bytes"] for l in b["levels"])]
    assert level_a == level_b
    assert gatun.validate(py)["valid"]


def test_levels_and_options(tmp_path, converted):
    mesh = gatun.read(converted["bunny"])
    one = tmp_path / "one.gtn"
    gatun.write(one, mesh.points, mesh.tets, levels=0, merge_tree=False)
    info = gatun.info(one, merge_tree=True)
    assert len(info["levels"]) == 1 and info["merge_tree"] is None
    two = tmp_path / "two.gtn"
    gatun.write(two, mesh.points, mesh.tets, point_data=mesh.point_data, levels=2, simplify_field="none")
    info = gatun.info(two, merge_tree=True)
    assert [l["ratio"] for l in info["levels"]] == pytest.approx([0.0, 0.5, 0.75], abs=1e-3)
    assert info["merge_tree"]["field"] == ""


def test_greedy_ranking_is_the_commands_flag(gtn, converted, tmp_path):
    cli = tmp_path / "cli.gtn"
    gtn.run("convert", converted["bunny"], "-o", cli, "--greedy-ranking")
    mesh = gatun.read(converted["bunny"])
    greedy, lazy = tmp_path / "greedy.gtn", tmp_path / "lazy.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the constant field the ranking skips, as gtn says
        gatun.write(greedy, mesh.points, mesh.tets, point_data=mesh.point_data, cell_data=mesh.cell_data,
                    metadata=mesh.metadata, greedy_ranking=True)
        gatun.write(lazy, mesh.points, mesh.tets, point_data=mesh.point_data, cell_data=mesh.cell_data,
                    metadata=mesh.metadata)
    a, b, c = gatun.info(cli, merge_tree=True), gatun.info(greedy, merge_tree=True), gatun.info(lazy, merge_tree=True)
    assert sections(a) == sections(b)
    assert a["merge_tree"] == b["merge_tree"]
    assert c["merge_tree"]["error_quantiles"] != b["merge_tree"]["error_quantiles"]


def test_types_and_metadata_round_trip(tmp_path):
    rng = np.random.default_rng(7)
    points = rng.random((200, 3)).astype(np.float32)
    # A fan of tetrahedra around point 0 over random triangles would overlap: use a Delaunay-free
    # mesh of disjoint tetrahedra instead (each uses four points of its own).
    tets = np.arange(200).reshape(50, 4)
    point_data = {"t": rng.random(200), "v": rng.integers(-5, 5, (200, 2)).astype(np.int16)}
    cell_data = {"region": np.arange(50, dtype=np.uint8)}
    path = tmp_path / "types.gtn"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gatun.write(path, points, tets, point_data, cell_data, levels=0, metadata={"case": "types"})
    mesh = gatun.read(path)
    assert mesh.points.dtype == np.float32
    assert mesh.point_data["t"].dtype == np.float64
    assert mesh.point_data["v"].dtype == np.int16 and mesh.point_data["v"].shape == (200, 2)
    assert mesh.cell_data["region"].dtype == np.uint8
    assert mesh.metadata["case"] == "types"
    # Up to renumbering: each tetrahedron keeps its points (as a set) and its region.
    key = {tuple(sorted(map(tuple, points[t].tolist()))): r for t, r in zip(tets, cell_data["region"])}
    got = {tuple(sorted(map(tuple, mesh.points[t].tolist()))): r for t, r in zip(mesh.tets, mesh.cell_data["region"])}
    assert got == key
    flips = [str(w.message) for w in caught if "flipped" in str(w.message)]
    negative = sum(np.linalg.det(points[t[1:]] - points[t[0]]) < 0 for t in tets)
    assert (flips == []) == (negative == 0)
    if negative:
        assert f"flipped {negative} tetrahedra" in flips[0]


def test_bad_input_is_refused_and_nothing_written(tmp_path):
    points = np.eye(4, 3)
    path = tmp_path / "bad.gtn"
    with pytest.raises(gatun.UsageError, match="tetrahedron 0 refers to point 7"):
        gatun.write(path, points, [[0, 1, 2, 7]])
    with pytest.raises(gatun.UsageError, match=r"points must be an \(n, 3\) array"):
        gatun.write(path, points[:, :2], [[0, 1, 2, 3]])
    with pytest.raises(gatun.UsageError, match="point field 'f': shape must be"):
        gatun.write(path, points, [[0, 1, 2, 3]], point_data={"f": np.zeros(3)})
    with pytest.raises(gatun.UsageError, match="not one of int8"):
        gatun.write(path, points, [[0, 1, 2, 3]], cell_data={"c": np.array(["x"])})
    with pytest.raises(gatun.InvalidDataError, match="not finite|finite"):
        gatun.write(path, np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]]), [[0, 1, 2, 3]])
    assert not path.exists()
    with pytest.raises(gatun.IoError):
        gatun.write(tmp_path / "no" / "such" / "dir.gtn", points, [[0, 1, 2, 3]])
    assert list(tmp_path.iterdir()) == []


def test_a_mesh_with_errors_of_its_own_is_refused_unless_kept(tmp_path):
    # Two tetrahedra overlapping: validate() would call the file invalid, so nothing is written, unless
    # keep_invalid asks for it (then with a warning, and validate() reports the errors).
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.1, 0.1, 0.1]])
    tets = [[0, 1, 2, 3], [0, 1, 2, 4]]
    path = tmp_path / "overlap.gtn"
    with pytest.raises(gatun.InvalidDataError, match="errors that `gtn validate` would report.*BOUNDARY_ORIENTATION"):
        gatun.write(path, points, tets)
    assert not path.exists()
    with pytest.warns(UserWarning, match="BOUNDARY_ORIENTATION"):
        gatun.write(path, points, tets, keep_invalid=True)
    report = gatun.validate(path)
    assert not report["valid"]
    assert any(m["code"] == "BOUNDARY_ORIENTATION" for m in report["messages"])


def test_what_the_import_step_changes_is_said(tmp_path):
    # A flat tetrahedron on a face of a solid one: listed one way it agrees with its neighbour, the
    # other way it is turned around, and write says so as `gtn convert` does (the note was dropped).
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]], dtype=np.float64)
    said = []
    for flat in ([0, 1, 2, 4], [0, 2, 1, 4]):
        tets = np.array([[0, 1, 2, 3], flat], dtype=np.int64)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            gatun.write(tmp_path / "flat.gtn", points, tets, levels=0, merge_tree=False)
        said.append([str(w.message) for w in caught if "reoriented to agree with their neighbours" in str(w.message)])
    assert sorted(len(s) for s in said) == [0, 1], said


def cpu_ticks_by_thread():
    ticks = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except FileNotFoundError:  # a thread that ended meanwhile
            continue
        ticks[int(tid)] = int(fields[11]) + int(fields[12])  # utime + stime
    return ticks


def other_threads_ticks(fn):
    """CPU clock ticks that threads other than the calling one spent while fn ran."""
    me = threading.get_native_id()
    before = cpu_ticks_by_thread()
    fn()
    after = cpu_ticks_by_thread()
    return sum(t - before.get(tid, 0) for tid, t in after.items() if tid != me)


@pytest.mark.skipif(not os.path.isdir("/proc/self/task") or len(os.sched_getaffinity(0)) < 2,
                    reason="needs Linux's per-thread CPU times and two cores")
def test_threads_bounds_tbb_for_the_call(converted, tmp_path):
    # The ranking runs in parallel (TBB): threads=1 keeps all of it on the calling thread, and the
    # limit ends with the call.
    mesh = gatun.read(converted["bluntfin"], level=2)
    # TBB's workers, busy in the read, spin a moment before they sleep: wait until they are idle, or
    # their last ticks would count against the call measured next.
    for _ in range(40):
        if other_threads_ticks(lambda: time.sleep(0.05)) == 0:
            break

    def write(threads):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            gatun.write(tmp_path / f"t{threads}.gtn", mesh.points, mesh.tets, point_data=mesh.point_data,
                        levels=1, threads=threads)

    # A worker that wakes for a moment can be charged a whole clock tick, now and then: a limit that
    # works leaves some call of three with no tick on another thread; one that does not, none.
    assert min(other_threads_ticks(lambda: write(1)) for _ in range(3)) == 0
    assert other_threads_ticks(lambda: write(None)) > 0
    # The same file whatever the threads (the provenance names the output, so compare levels).
    a, b = gatun.info(tmp_path / "t1.gtn"), gatun.info(tmp_path / "tNone.gtn")
    assert sections(a) == sections(b)
    assert gatun.read(tmp_path / "t1.gtn").tets.tobytes() == gatun.read(tmp_path / "tNone.gtn").tets.tobytes()
    with pytest.raises(gatun.UsageError, match="threads 0 must be 1 or more"):
        gatun.write(tmp_path / "t0.gtn", mesh.points, mesh.tets, threads=0)
