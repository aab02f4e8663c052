"""Fixtures of the gatun tests: the gtn command built beside the module, the real datasets
(GTN_DATA_DIR, default ../shared/data beside the checkout) converted once per session."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _gtn_binary():
    for candidate in (os.environ.get("GTN_BINARY"), ROOT / "build" / "gtn", shutil.which("gtn")):
        if candidate and Path(candidate).is_file():
            return str(candidate)
    pytest.exit("the gtn command is not built (set GTN_BINARY)", returncode=1)


def _data_dir():
    for candidate in (os.environ.get("GTN_DATA_DIR"), os.environ.get("GTN_DEFAULT_DATA_DIR"), ROOT.parent / "shared" / "data"):
        if candidate and Path(candidate).is_dir():
            return Path(candidate)
    pytest.exit("the datasets are missing (set GTN_DATA_DIR)", returncode=1)


class Gtn:
    """Runs the gtn command."""

    def __init__(self, binary):
        self.binary = binary

    def run(self, *args, check=True, env=None):
        r = subprocess.run([self.binary, *map(str, args)], capture_output=True, text=True, env=env)
        if check and r.returncode != 0:
            raise AssertionError(f"gtn {' '.join(map(str, args))} failed ({r.returncode}): {r.stderr}")
        return r

    def json(self, *args):
        return json.loads(self.run(*args).stdout)


@pytest.fixture(scope="session")
def gtn():
    return Gtn(_gtn_binary())


@pytest.fixture(scope="session")
def data_dir():
    return _data_dir()


@pytest.fixture(scope="session")
def converted(gtn, data_dir, tmp_path_factory):
    """The real datasets converted by `gtn convert`: name -> path of the .gtn file. Blunt fin asks for
    three levels (automatic levels give a grid only its coarse level of about 5000 tetrahedra), so that reading
    levels 1 to 3 of a grid file is tested."""
    out = tmp_path_factory.mktemp("converted")
    files = {
        "bunny": [data_dir / "medit" / "bunny.mesh"],
        "bluntfin": [data_dir / "plot3d" / "bluntfinxyz.bin", data_dir / "plot3d" / "bluntfinq.bin", "--levels", "3"],
    }
    paths = {}
    for name, inputs in files.items():
        path = out / f"{name}.gtn"
        gtn.run("convert", *inputs, "-o", path)
        paths[name] = path
    return paths
