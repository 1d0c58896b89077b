"""Where the tests find isochor: the source tree and the command line (CTest sets both)."""
import os

import isochor

SOURCE = os.environ.get("ISOCHOR_SOURCE", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
EXE = os.environ.get("ISOCHOR_EXE", isochor.executable)
SWING = os.path.join(SOURCE, "demos", "swing.toml")
JELLY = os.path.join(SOURCE, "demos", "jelly_yup.toml")
