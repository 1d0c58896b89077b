"""The package's public face (docs/python.md): only the names of isochor.__all__ are public and
each is documented; the stub of the compiled part (isochor/_isochor.pyi) names what the compiled
part has, no more and no less; the version is the one CMake and pyproject.toml give."""
import ast
import inspect
import os
import re
import subprocess
import sys
import tomllib

import isochor
from paths import SOURCE

PACKAGE = os.path.join(SOURCE, "python", "isochor")


def public(names):
    return {n for n in names if not n.startswith("_")}


def test_only_the_names_of_all_are_public():
    assert public(vars(isochor)) == set(isochor.__all__)


def test_every_public_name_and_its_public_members_have_a_docstring():
    undocumented = []
    for name in isochor.__all__:
        obj = getattr(isochor, name)
        if name == "executable":
            continue  # a str: documented by the attribute docstring in __init__.py
        if not (obj.__doc__ or "").strip():
            undocumented.append(name)
        if inspect.isclass(obj) and not issubclass(obj, Exception):
            for member, value in vars(obj).items():
                if member.startswith("_") or not (callable(value) or isinstance(value, property) or
                                                   hasattr(value, "__get__")):
                    continue
                if not (getattr(value, "__doc__", None) or "").strip():
                    undocumented.append(f"{name}.{member}")
    assert undocumented == []


def stub_names(tree):
    """Top-level names and Scene's members of the stub."""
    top, scene = set(), set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
            if node.name == "Scene":
                scene = {m.name for m in node.body if isinstance(m, ast.FunctionDef)}
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
    return top, scene


def test_the_stub_names_what_the_compiled_part_has():
    with open(os.path.join(PACKAGE, "_isochor.pyi")) as f:
        top, scene = stub_names(ast.parse(f.read()))
    core = isochor._api._core()
    assert top == public(dir(core))
    assert scene == public(dir(core.Scene))
    # The stub's properties are properties of the compiled Scene, its methods are not.
    with open(os.path.join(PACKAGE, "_isochor.pyi")) as f:
        cls = next(n for n in ast.parse(f.read()).body if isinstance(n, ast.ClassDef) and n.name == "Scene")
    for m in cls.body:
        if isinstance(m, ast.FunctionDef):
            is_property = any(isinstance(d, ast.Name) and d.id == "property" for d in m.decorator_list)
            assert isinstance(inspect.getattr_static(core.Scene, m.name), property) == is_property, m.name


def test_the_package_is_typed():
    assert os.path.isfile(os.path.join(PACKAGE, "py.typed"))


def test_the_version_is_cmakes_and_pyprojects():
    with open(os.path.join(SOURCE, "CMakeLists.txt")) as f:
        cmake = re.search(r"project\(isochor VERSION ([0-9.]+)", f.read()).group(1)
    with open(os.path.join(SOURCE, "pyproject.toml"), "rb") as f:
        assert tomllib.load(f)["project"]["version"] == cmake == isochor.__version__


def test_python_m_isochor_is_the_command_line():
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(isochor.__file__)))
    p = subprocess.run([sys.executable, "-m", "isochor", "--version"], capture_output=True, text=True, env=env)
    assert p.returncode == 0 and p.stdout.startswith(isochor.__version__ + " ("), p.stdout + p.stderr
    p = subprocess.run([sys.executable, "-m", "isochor", "run", "no_such_scene.toml"], capture_output=True, text=True,
                       env=env)
    assert p.returncode != 0 and "no_such_scene.toml" in p.stderr
