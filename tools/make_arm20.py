"""Write models/arm20.xml, the 20-link planar arm of Fig. 11, from somarm.tasks.assets.arm_spec.

Usage: python tools/make_arm20.py [--check]
  --check  compare the file with a fresh generation instead of writing it (exit 1 if they differ).
"""

from __future__ import annotations

import argparse
import sys

from somarm.io import atomic_write_text
from somarm.tasks.assets import arm20_xml, model_path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    args = parser.parse_args(argv)
    path = model_path("arm2").with_name("arm20.xml")
    text = arm20_xml()
    if args.check:
        same = path.is_file() and path.read_text() == text
        print(f"{path}: {'up to date' if same else 'differs from the generator'}")
        return 0 if same else 1
    atomic_write_text(path, text)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
