"""Write ``docs/vehicle.md`` from the vehicle contract (``vehicle_contract/contract.py``).

The page is generated, never edited: ``tests/vehicle_contract/test_contract.py`` fails when the
committed page differs. After a contract change, run (from the repository root)::

    .venv/bin/python scripts/gen_vehicle_doc.py [ROOT]

``nemesys contract --markdown`` prints the same page.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
from collections.abc import Sequence

from vehicle_contract.doc import write


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument(
        "root",
        nargs="?",
        type=pathlib.Path,
        default=pathlib.Path(__file__).resolve().parents[1],
        help="the repository root (default: this script's)",
    )
    args = parser.parse_args(argv)
    print(write(args.root))
    return 0


if __name__ == "__main__":
    sys.exit(main())
