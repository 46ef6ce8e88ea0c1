#!/usr/bin/python3
"""tools/make_scoop.py is reproducible: regenerating the scoop gives the committed bytes."""

import filecmp
import os
import subprocess
import sys

from cli_check import test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    with test_dir("make_scoop") as out:
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "make_scoop.py"),
                        "--out-dir", out], check=True)
        failed = [name for name in ("scoop.stl", "scoop.obj")
                  if not filecmp.cmp(os.path.join(out, name),
                                     os.path.join(ROOT, "assets", name), shallow=False)]
    if failed:
        print("make_scoop_test: regenerated %s differ from assets/ (run tools/make_scoop.py)"
              % ", ".join(failed))
        return 1
    print("make_scoop_test: scoop.stl and scoop.obj regenerate byte for byte")
    return 0


if __name__ == "__main__":
    sys.exit(main())
