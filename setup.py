"""The build behind `pip install .` (pyproject.toml holds the metadata): CMake builds the compiled
part (_isochor) and the isochor program in build/ (ISOCHOR_BUILD_DIR names another; a configured
tree is built as it is, so `make build` and pip share one), and the package gets them beside its
Python files: isochor/_isochor*.so, isochor/bin/isochor, isochor/tools/ and isochor/viewer/ (the
page of `isochor view`), which they find by their own location. setuptools' own build files go under that tree too, so the source tree keeps
only what git has."""
import glob
import os
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = os.path.dirname(os.path.abspath(__file__))
BUILD = os.path.abspath(os.environ.get("ISOCHOR_BUILD_DIR") or os.path.join(SOURCE, "build"))
PIP_BUILD = os.path.join(BUILD, "pip")


class CMakeBuild(build_ext):
    """Builds _isochor and isochor with CMake and copies them, and tools/, into the package."""

    def build_extension(self, ext):
        if not os.path.exists(os.path.join(BUILD, "CMakeCache.txt")):
            subprocess.check_call(["cmake", "-S", SOURCE, "-B", BUILD, "-DCMAKE_BUILD_TYPE=Release"])
        subprocess.check_call(["cmake", "--build", BUILD, "-j", str(os.cpu_count() or 1),
                               "--target", "_isochor", "isochor", "isochor_viewer"])
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        built = glob.glob(os.path.join(BUILD, "python", "isochor", "_isochor*.so"))
        if not built:
            sys.exit(f"isochor: {BUILD} built no Python module (is pybind11-dev installed? "
                     "tools/install-deps.sh installs it)")
        if not built[0].endswith(suffix):
            sys.exit(f"isochor: {built[0]} is built for another Python than {sys.executable} (expected *{suffix}; "
                     "make the environment from Debian's python3: /usr/bin/python3 -m venv --system-site-packages)")
        target = self.get_ext_fullpath(ext.name)
        package = os.path.dirname(target)
        os.makedirs(os.path.join(package, "bin"), exist_ok=True)
        shutil.copy2(built[0], target)
        shutil.copy2(os.path.join(BUILD, "isochor"), os.path.join(package, "bin", "isochor"))  # CMAKE_RUNTIME_OUTPUT_DIRECTORY
        viewer = os.path.join(BUILD, "viewer", "static")
        if os.path.isfile(os.path.join(viewer, "viewer.js")):  # isochor view's page (npm at build time)
            shutil.rmtree(os.path.join(package, "viewer"), ignore_errors=True)
            shutil.copytree(viewer, os.path.join(package, "viewer"))
        tools = os.path.join(package, "tools")
        shutil.rmtree(tools, ignore_errors=True)
        shutil.copytree(os.path.join(SOURCE, "tools"), tools, ignore=shutil.ignore_patterns(
            "*.pyc", "__pycache__", "*.sh", "*.cpp", "CMakeLists.txt"))


os.makedirs(PIP_BUILD, exist_ok=True)
setup(
    packages=["isochor"],
    package_dir={"": "python"},
    package_data={"isochor": ["py.typed", "*.pyi"]},
    ext_modules=[Extension("isochor._isochor", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": PIP_BUILD}, "egg_info": {"egg_base": PIP_BUILD}},
    zip_safe=False,
)
