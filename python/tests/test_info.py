"""gatun.info / gatun.validate return what the CLI prints; `gtn info --merge-tree` prints a table
whose numbers agree with --json; --plot and gatun.plot_merge_tree draw the error curve."""

import re
import struct

import numpy as np
import pytest

import gatun


@pytest.mark.parametrize("name", ["bunny", "bluntfin"])
def test_info_and_validate_equal_cli(gtn, converted, name):
    path = str(converted[name])
    assert gatun.info(path) == gtn.json("info", "--json", path)
    assert gatun.info(path, merge_tree=True) == gtn.json("info", "--json", "--merge-tree", path)
    assert gatun.validate(path) == gtn.json("validate", "--json", path)
    assert gatun.validate(path, quick=True) == gtn.json("validate", "--json", "--quick", path)


def test_info_of_mesh_files_equals_cli(gtn, data_dir):
    files = [data_dir / "plot3d" / "bluntfinxyz.bin", data_dir / "plot3d" / "bluntfinq.bin"]
    assert gatun.info(files) == gtn.json("info", "--json", *files)


def table(text):
    """The merge-tree table of `gtn info --merge-tree`: labelled lines and level rows."""
    lines = text.split("  merge tree (level 0)\n", 1)[1].splitlines()
    rows, labelled, quantiles = [], {}, None
    for i, line in enumerate(lines):
        if not line.startswith("    "):
            break
        body = line[4:]
        if body.startswith("level "):
            continue
        if re.match(r"\d+ ", body):
            rows.append(body.split())
        elif body.startswith("error quantiles"):
            names = body[len("error quantiles"):].split()
            quantiles = dict(zip(names, map(float, lines[i + 1].split())))
        elif body[:20].strip():
            labelled[body[:20].strip()] = body[20:]
    return labelled, quantiles, rows


def test_merge_tree_table_agrees_with_json(gtn, converted):
    path = converted["bluntfin"]
    text = gtn.run("info", "--merge-tree", path).stdout
    mt = gtn.json("info", "--json", "--merge-tree", path)["merge_tree"]
    labelled, quantiles, rows = table(text)
    assert labelled["merges"].startswith(f"{mt['merges']} of ")
    assert f"(boundary {mt['boundary_merges']}), {mt['tets_removed']} tetrahedra removed" in labelled["merges"]
    assert labelled["roots"] == str(mt["roots"])
    assert labelled["depth"] == f"max {mt['depth']['max']}, mean {mt['depth']['mean']:.3f}"
    assert labelled["fan-out"] == f"max {mt['fanout']['max']}, mean {mt['fanout']['mean']:.3f}"
    assert set(quantiles) == set(mt["error_quantiles"])
    for k, v in mt["error_quantiles"].items():
        assert quantiles[k] == pytest.approx(v, rel=1e-3, abs=1e-300)
    assert len(rows) == len(mt["levels"]) == len(gatun.info(path)["levels"]) >= 3
    for row, level in zip(rows, mt["levels"]):
        assert int(row[0]) == level["level"]
        assert float(row[1]) == pytest.approx(level["ratio"], abs=1e-6)
        assert [int(x) for x in row[2:6]] == [level["points"], level["tets"], level["bytes"], level["merges"]]
        if level["largest_error"] is None:
            assert row[6] == "-"
        else:
            assert float(row[6]) == pytest.approx(level["largest_error"], rel=1e-3)
    # The per-level numbers are the file's (info's levels) and the largest errors the curve's.
    info_levels = gatun.info(path)["levels"]
    for level, stored in zip(mt["levels"], info_levels):
        assert (level["tets"], level["bytes"], level["ratio"]) == (stored["tets"], stored["bytes"], stored["ratio"])
    curve = mt["error_curve"]
    assert max(p["error"] for p in curve) == mt["error_quantiles"]["max"]
    for level in mt["levels"][1:]:
        assert level["largest_error"] == max(p["error"] for p in curve if p["merges"] <= level["merges"])
    assert mt["levels"][0]["largest_error"] is None
    assert all(a["largest_error"] <= b["largest_error"] for a, b in zip(curve, curve[1:]))
    assert gatun.merge_tree_stats(path) == mt


def png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def assert_drawn(path):
    import matplotlib.image

    assert png_size(path) == (800, 500)
    pixels = matplotlib.image.imread(str(path))[:, :, :3]
    colours = np.unique((pixels * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 8
    # Something is drawn: more than 2 % of the pixels are not white, and the curve's blue is there.
    assert np.mean(np.any(pixels < 0.95, axis=2)) > 0.02
    blue = (pixels[:, :, 2] > 0.5) & (pixels[:, :, 0] < 0.3)
    assert blue.sum() > 300


def test_cli_plot(gtn, converted, tmp_path):
    png = tmp_path / "errors.png"
    r = gtn.run("info", converted["bluntfin"], "--plot", png)
    assert "merge tree (level 0)" not in r.stdout  # --plot alone keeps the usual report
    assert_drawn(png)


def test_python_plot(converted, tmp_path):
    png = tmp_path / "errors.png"
    fig = gatun.plot_merge_tree(converted["bluntfin"], png)
    assert fig is not None
    assert_drawn(png)


def test_plot_refusals(gtn, converted, tmp_path):
    flat = tmp_path / "flat.gtn"
    gtn.run("convert", converted["bunny"], "-o", flat, "--levels", "0", "--no-merge-tree")
    r = gtn.run("info", flat, "--plot", tmp_path / "x.png", check=False)
    assert r.returncode == 2 and "stores no merge tree" in r.stderr
    with pytest.raises(gatun.UsageError, match="stores no merge tree"):
        gatun.plot_merge_tree(flat, tmp_path / "y.png")
    assert gatun.merge_tree_stats(flat) is None
    # Without gnuplot, a clear error and no image.
    r = gtn.run("info", converted["bunny"], "--plot", tmp_path / "z.png", check=False, env={"PATH": str(tmp_path)})
    assert r.returncode == 3 and "gnuplot is not installed" in r.stderr
    assert not (tmp_path / "z.png").exists() and not (tmp_path / "x.png").exists()
