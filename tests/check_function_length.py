#!/usr/bin/env python3
"""Every function of the project's own code is at most 80 lines (docs/architecture.md: drivers
split along the seams their comments name). C++ through universal-ctags (its `end:` field), Python
through the ast module. Tests are left out: a test reads top to bottom.

Prints one line per function over the limit and exits 1 if there is any; exits 77 (CTest's skip)
when universal-ctags is not installed (apt-get install universal-ctags).

Usage: check_function_length.py SOURCE_ROOT [LIMIT]
"""
import ast
import os
import shutil
import subprocess
import sys

CPP_FOLDERS = ["base", "core", "integrators", "models", "scene", "apps", "python/src", "bench"]
PY_FOLDERS = ["tools", "python/isochor", "python/examples", "bench", "studies", "demos"]


def cpp_functions(root, folders):
    """(file, name, first line, lines) of every C++ function definition ctags finds."""
    ctags = shutil.which("ctags-universal") or shutil.which("ctags")
    version = subprocess.run([ctags, "--version"], capture_output=True, text=True).stdout if ctags else ""
    if "Universal Ctags" not in version:
        print("check_function_length: universal-ctags is not installed (apt-get install universal-ctags)")
        sys.exit(77)
    paths = [os.path.join(root, f) for f in folders if os.path.isdir(os.path.join(root, f))]
    out = subprocess.run([ctags, "-R", "--languages=C++", "--c++-kinds=f", "--fields=+ne", "-f", "-", *paths],
                         capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        fields = line.split("\t")
        extra = dict(f.split(":", 1) for f in fields[3:] if ":" in f)
        if "line" in extra and "end" in extra:
            first, last = int(extra["line"]), int(extra["end"])
            yield os.path.relpath(fields[1], root), fields[0], first, last - first + 1


def py_functions(root, folders):
    for folder in folders:
        for base, _, files in os.walk(os.path.join(root, folder)):
            for name in files:
                if not name.endswith(".py"):
                    continue
                path = os.path.join(base, name)
                with open(path, encoding="utf-8") as f:
                    tree = ast.parse(f.read(), path)
                for node in ast.walk(tree):
                    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                        yield os.path.relpath(path, root), node.name, node.lineno, node.end_lineno - node.lineno + 1


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__.strip().splitlines()[-1])
    root = sys.argv[1]
    limit = int(sys.argv[2]) if len(sys.argv) == 3 else 80
    long = [f for f in list(cpp_functions(root, CPP_FOLDERS)) + list(py_functions(root, PY_FOLDERS)) if f[3] > limit]
    for path, name, first, lines in sorted(long):
        print(f"{path}:{first}: {name} is {lines} lines (at most {limit})")
    sys.exit(1 if long else 0)


if __name__ == "__main__":
    main()
