"""pip install --no-build-isolation .   builds the Python package gatun (python/) with the project's
CMake: the library and the pybind11 module _gatun, for the Python that runs pip. It needs what the
C++ build needs plus Debian's pybind11-dev and python3-dev; numpy comes from python3-numpy.
Extra CMake options: CMAKE_ARGS="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"; parallel jobs:
CMAKE_BUILD_PARALLEL_LEVEL=N."""

import glob
import os
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def project_version():
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        return re.search(r"project\(gatun VERSION ([0-9.]+)", f.read()).group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        configure = [
            "cmake", "-S", ROOT, "-B", build_dir,
            "-DCMAKE_BUILD_TYPE=Release",
            "-DGTN_BUILD_PYTHON=ON", "-DGTN_BUILD_TESTS=OFF", "-DGTN_BUILD_BENCH=OFF",
            f"-DPython_EXECUTABLE={sys.executable}",
        ] + shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", build_dir, "--target", "gatun_python"])
        built = glob.glob(os.path.join(build_dir, "python", "gatun", "_gatun*.so"))
        if len(built) != 1:
            raise RuntimeError(f"setup.py: expected one _gatun module in {build_dir}/python/gatun, found {built}")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)


setup(
    name="gatun",
    version=project_version(),
    description="Compressed tetrahedral meshes (.gtn): read, write, inspect; a meshio format",
    license="LGPL-3.0-or-later",
    packages=["gatun"],
    package_dir={"": "python"},
    ext_modules=[Extension("gatun._gatun", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    python_requires=">=3.9",
    zip_safe=False,
)
