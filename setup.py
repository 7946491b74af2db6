"""The extension module lidarsurf._lidarsurf, built by the project's own CMake (pyproject.toml
holds the package's metadata). Environment: LIDARSURF_CMAKE_ARGS adds CMake options, and
LIDARSURF_BUILD_JOBS sets the parallel jobs (default: every core)."""
import os
import pathlib
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = pathlib.Path(self.build_temp).resolve() / "cmake"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",  # the interpreter pip runs: a venv's, or the system's
            "-DLIDARSURF_BUILD_TESTS=OFF", "-DLIDARSURF_BUILD_BENCH=OFF", "-DLIDARSURF_BUILD_PYTHON=ON",
        ] + shlex.split(os.environ.get("LIDARSURF_CMAKE_ARGS", ""))
        jobs = os.environ.get("LIDARSURF_BUILD_JOBS", str(os.cpu_count() or 1))
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", str(build), "--target", "_lidarsurf", "-j", jobs])
        built = sorted((build / "python" / "lidarsurf").glob("_lidarsurf*.so"))
        if not built:
            raise RuntimeError(f"CMake built no _lidarsurf module in {build / 'python' / 'lidarsurf'}")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[-1], target)


setup(ext_modules=[CMakeExtension("lidarsurf._lidarsurf")], cmdclass={"build_ext": CMakeBuild})
