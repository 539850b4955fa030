"""Write ``docs/live.md`` from the ``/ws`` message models (``backend/api/schemas/live.py``).

The page is generated, never edited: ``tests/backend/test_live_messages.py`` fails when the
committed page differs. After a change to a message (or a shape one carries, such as the
command record), run (from the repository root)::

    .venv/bin/python scripts/gen_live_doc.py [ROOT]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
from collections.abc import Sequence

from backend.api.live_doc import write


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
