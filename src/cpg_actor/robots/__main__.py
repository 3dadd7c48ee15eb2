"""``python -m cpg_actor.robots [--check]``: regenerate (or check) the shipped robot files."""

from __future__ import annotations

import argparse
import sys

from cpg_actor.robots.assets import stale_assets, write_assets


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m cpg_actor.robots", description=__doc__)
    parser.add_argument("--check", action="store_true", help="only report stale files (exit 1)")
    args = parser.parse_args(argv)
    if args.check:
        stale = stale_assets()
        for path in stale:
            print(f"stale: {path}")
        return 1 if stale else 0
    for path in write_assets():
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
