"""This console's name among the consoles sharing a mission log.

``console_name`` in the settings wins. Without it the name is kept beside the mission log's
file (``<db_path>.console``, as the operator token is: ``backend/token_file.py``), made on
first use from the host name and a few random characters, so that a console that restarts is
the same console (control it held stays its own, if it is back within the timeout) and two
consoles on one host (each with its own ``db_path``) are two. An in-memory log gets a fresh
name at each start. The name is no secret: the file is plain text.
"""

from __future__ import annotations

import re
import secrets
import socket
from pathlib import Path
from typing import Final

from backend.settings import Settings

#: What follows the mission log's file name in the name file's name.
SUFFIX: Final = ".console"
#: A console's name (the settings' rule): letters, digits, ``.``, ``_``, ``-``.
NAME_FORM: Final = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")


class ConsoleNameError(Exception):
    """The name file cannot be read or written; the message names it and the fix."""


def new_name() -> str:
    """The host's name (its first label, cleaned to the allowed characters) and 4 random hex
    characters."""
    host = re.sub(r"[^A-Za-z0-9._-]", "-", socket.gethostname().split(".")[0]).strip("-._")
    return f"{(host or 'console')[:40]}-{secrets.token_hex(2)}"


def recovered_by(settings: Settings) -> str | None:
    """Whose commands left on their way a start makes ``interrupted``
    (:meth:`backend.mission_log.store.MissionLog.recover_interrupted`): on a log consoles
    share (PostgreSQL), this console's own, by name (another console's are on their way);
    on a SQLite file, every one (None).

    Raises:
        ConsoleNameError: as :func:`console_name`.
    """
    return console_name(settings) if settings.database_url else None


def name_path(db_path: Path) -> Path:
    return db_path.with_name(db_path.name + SUFFIX)


def console_name(settings: Settings) -> str:
    """The name of the console of ``settings`` (see the module's doc).

    Raises:
        ConsoleNameError: the kept name cannot be read or a new one cannot be written, or
            the file holds something that is not a name.
    """
    if settings.console_name:
        return settings.console_name
    if str(settings.db_path) == ":memory:":
        return new_name()
    path = name_path(settings.db_path)
    try:
        kept = path.read_text(encoding="utf-8").strip()
    except FileNotFoundError:
        kept = None
    except (OSError, UnicodeDecodeError) as err:
        raise ConsoleNameError(
            f"console name file {path} cannot be read ({err}): fix it, or set NEMESYS_CONSOLE_NAME"
        ) from None
    if kept is not None:
        if not NAME_FORM.fullmatch(kept):
            raise ConsoleNameError(
                f"console name file {path} holds {kept[:40]!r}, not a name (letters, digits, "
                "'.', '_' or '-', at most 64): fix it, delete it for a new one, or set "
                "NEMESYS_CONSOLE_NAME"
            )
        return kept
    name = new_name()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("x", encoding="utf-8") as out:
            out.write(name + "\n")
    except FileExistsError:  # another console starting on the same file made it just now
        return path.read_text(encoding="utf-8").strip()
    except OSError as err:
        raise ConsoleNameError(
            f"console name file {path} cannot be written ({err}): set NEMESYS_CONSOLE_NAME"
        ) from None
    return name
