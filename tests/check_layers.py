#!/usr/bin/env python3
"""The dependency rule of docs/architecture.md, checked over the #include lines.

Each library sees only the libraries below it:

    base  <-  core  <-  models  <-  scene  <-  app (apps/)  <-  the CLI, the Python module
    base  <-  integrators  <-  models

`integrators/` sees neither meshes nor materials (only the ConstrainedSystem interface), so a
pendulum or a multibody problem is integrated by the same code as a tet mesh. Public headers live
in FOLDER/include/isochor/LIBRARY/ and are included by that full name; a library's private headers
(FOLDER/src/*.hpp) are included by its own sources and the tests only. No two source folders share
a name. Prints one line per violation and exits 1 if there is any.

Usage: check_layers.py SOURCE_ROOT
"""
import os
import re
import sys

# folder -> (library name, libraries it may include)
LAYERS = {
    "base": ("base", {"base"}),
    "core": ("core", {"base", "core"}),
    "integrators": ("integrators", {"base", "integrators"}),
    "models": ("models", {"base", "core", "integrators", "models"}),
    "scene": ("scene", {"base", "core", "integrators", "models", "scene"}),
    "apps": ("app", {"base", "core", "integrators", "models", "scene", "app"}),
    "python": ("python", {"base", "core", "integrators", "models", "scene", "app"}),
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
SOURCE = (".cpp", ".hpp", ".h", ".cc")
GENERATED = {"isochor_git_revision.hpp"}  # written by cmake/git_revision.cmake into the build tree


def check_file(root, path, folder):
    lib, allowed = LAYERS[folder]
    rel = os.path.relpath(path, root)
    problems = []
    header_dir = os.path.join(folder, "include", "isochor")
    if rel.endswith((".hpp", ".h")) and rel.startswith(header_dir + os.sep):
        if not rel.startswith(os.path.join(header_dir, lib) + os.sep):
            problems.append(f"{rel}: a public header of {folder}/ outside isochor/{lib}/")
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            name = m.group(1)
            parts = name.split("/")
            if parts[0] == "isochor":
                if len(parts) < 3:
                    problems.append(f"{rel}:{number}: \"{name}\": expected isochor/LIBRARY/NAME")
                elif parts[1] not in allowed:
                    problems.append(f"{rel}:{number}: \"{name}\": {folder}/ may include only "
                                    + ", ".join(sorted(allowed)))
            elif name not in GENERATED and not os.path.exists(os.path.join(os.path.dirname(path), name)):
                problems.append(f"{rel}:{number}: \"{name}\": not beside this file (a header of another "
                                "library is included as isochor/LIBRARY/NAME)")
    return problems


def duplicate_folders(root):
    """Folders named alike in two places (the header folders isochor/LIBRARY/ aside)."""
    seen = {folder: [folder] for folder in LAYERS}
    for folder in LAYERS:
        for dirpath, dirnames, _ in os.walk(os.path.join(root, folder)):
            rel = os.path.relpath(dirpath, root)
            if os.path.join("include", "isochor") in rel:
                dirnames[:] = []
                continue
            for d in dirnames:
                if d not in ("include", "src", "isochor", "__pycache__"):
                    seen.setdefault(d, []).append(os.path.join(rel, d))
    return [f"folder name \"{name}\" used twice: " + ", ".join(where)
            for name, where in sorted(seen.items()) if len(where) > 1]


def violations(root):
    problems = []
    for folder in LAYERS:
        top = os.path.join(root, folder)
        for dirpath, _, filenames in os.walk(top):
            for name in sorted(filenames):
                if name.endswith(SOURCE):
                    problems += check_file(root, os.path.join(dirpath, name), folder)
    return problems + duplicate_folders(root)


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    problems = violations(sys.argv[1])
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
