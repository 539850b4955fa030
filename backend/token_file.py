"""The operator token kept beside the mission log, so that it survives a console restart.

A page opened with the printed URL keeps working after the console restarts (a crash, a
reboot of the ship's laptop): the token is read back from ``<mission log>.token``, e.g.
``.nemesys/missions.sqlite3.token``, instead of a new one being made at every start. The
file is created owner-only (0600) in one step (``O_CREAT | O_EXCL`` with the mode: never
readable by others, even for a moment) and read back only if it still is: a token file
that others could read, that belongs to another user, that is a link or holds no token is a
:class:`TokenFileError` naming the file and the fix, never replaced silently by a new token.

An explicit token (``NEMESYS_TOKEN``, ``token=`` in the settings file, a ``token`` given to
:class:`~backend.settings.Settings`) wins and no file is read or written. ``nemesys console
--new-token`` writes a new token over the kept one (a link the operator gave away is then no
longer good); pages holding the old one say so as soon as they reconnect. An in-memory log
(``:memory:``) has nowhere to keep a token: a fresh one per start.

POSIX only, as the console is.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import stat
from pathlib import Path
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:  # only the standard library at run time: ``nemesys`` imports this early
    from backend.settings import Settings

#: What follows the mission log's file name in the token file's name.
SUFFIX: Final = ".token"
#: What a kept token may be: URL-safe (it goes in the printed URL as it is), 16 to 256 long.
TOKEN_FORM: Final = re.compile(r"[A-Za-z0-9_-]{16,256}")
#: Random bytes in a new token (32 URL-safe characters).
TOKEN_BYTES: Final = 24
#: Owner read and write, nothing for the group or others.
OWNER_ONLY: Final = 0o600
#: The most of a token file that is read (bytes): a token is one short line.
MAX_READ_BYTES: Final = 4096
#: Flags of every open here: no following a link planted at the path, not inherited.
_NO_LINK: Final = os.O_NOFOLLOW | os.O_CLOEXEC
ROTATE_HINT: Final = "run `nemesys console --new-token` to write a new one"


class TokenFileError(Exception):
    """The token file at ``path`` cannot be used: ``problem`` (what is wrong), ``hint`` (what
    to do). The message: ``operator token file <path> <problem>: <hint>``."""

    def __init__(self, path: Path, problem: str, hint: str) -> None:
        super().__init__(f"operator token file {path} {problem}: {hint}")
        self.path = path
        self.problem = problem
        self.hint = hint


def token_path(db_path: Path) -> Path:
    """Where the token of the console whose mission log is ``db_path`` is kept."""
    return db_path.with_name(db_path.name + SUFFIX)


def with_kept_token(settings: Settings, *, rotate: bool = False) -> Settings:
    """``settings`` with the operator token to use: the explicit one if set, else the one kept
    beside the mission log (made on first use; a new one written when ``rotate``).

    Raises:
        TokenFileError: the file is unsafe or unreadable, or cannot be written; or ``rotate``
            with an explicit token (which one would be meant is not clear).
    """
    path = token_path(settings.db_path)
    if "token" in settings.model_fields_set:
        if rotate:
            raise TokenFileError(
                path,
                "is not used: the token is set explicitly (NEMESYS_TOKEN or the settings file)",
                "change that setting to change the token, or unset it to use --new-token",
            )
        return settings
    if str(settings.db_path) == ":memory:":
        return settings.model_copy(update={"token": new_token()})
    token = write_new(path) if rotate else kept_or_new(path)
    return settings.model_copy(update={"token": token})


def new_token() -> str:
    return secrets.token_urlsafe(TOKEN_BYTES)


def kept_or_new(path: Path) -> str:
    """The token kept at ``path``; a new one written there if there is no file yet."""
    token = read_token(path)
    if token is not None:
        return token
    _make_directory(path)
    token = new_token()
    try:
        _create(path, token)
    except FileExistsError:  # another console starting on the same log made it just now
        kept = read_token(path)
        if kept is None:  # gone again in between: the next start tries afresh
            raise _io_error(path, "disappeared while being created", None) from None
        return kept
    return token


def write_new(path: Path) -> str:
    """Write a new token at ``path`` (replacing a kept one in one step) and return it."""
    _make_directory(path)
    token = new_token()
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(4)}.new")
    _create(temporary, token)
    try:
        os.replace(temporary, path)
    except OSError as err:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise _io_error(path, "cannot be replaced", err) from None
    return token


def read_token(path: Path) -> str | None:
    """The token kept at ``path``, None if there is no such file.

    Raises:
        TokenFileError: the file is a link or not a regular file, belongs to another user,
            is open to the group or others, cannot be read, or holds no token.
    """
    try:
        fd = os.open(path, os.O_RDONLY | _NO_LINK)
    except FileNotFoundError:
        return None
    except OSError as err:
        if err.errno == errno.ELOOP:
            raise TokenFileError(
                path, "is a symbolic link", f"remove it and {ROTATE_HINT}"
            ) from None
        raise _unreadable(path, err) from None
    try:
        _check_safe(path, os.fstat(fd))  # the file opened: no swap between check and read
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(MAX_READ_BYTES + 1)
    except OSError as err:
        raise _unreadable(path, err) from None
    finally:
        os.close(fd)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        text = ""
    token = text.removesuffix("\n")
    if len(data) > MAX_READ_BYTES or not TOKEN_FORM.fullmatch(token):
        raise TokenFileError(
            path,
            "holds no operator token (one line of 16 to 256 characters A-Z a-z 0-9 _ - expected)",
            ROTATE_HINT,
        )
    return token


def _check_safe(path: Path, info: os.stat_result) -> None:
    if not stat.S_ISREG(info.st_mode):
        raise TokenFileError(path, "is not a regular file", f"remove it and {ROTATE_HINT}")
    if info.st_uid != os.getuid():
        raise TokenFileError(
            path,
            f"belongs to another user (uid {info.st_uid})",
            f"remove it and {ROTATE_HINT}, or run the console as its owner",
        )
    mode = stat.S_IMODE(info.st_mode)
    if mode & 0o077:
        raise TokenFileError(
            path,
            f"is open to other users (mode {mode:04o}, owner-only 0600 needed): the token in "
            "it may have been read",
            f"{ROTATE_HINT} (or `chmod 600 {path}` if nobody else could have read it)",
        )


def _create(path: Path, token: str) -> None:
    """A new file at ``path`` holding ``token``: 0600 from its creation.

    Raises:
        FileExistsError: ``path`` exists.
        TokenFileError: it cannot be created or written (nothing left behind).
    """
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NO_LINK, OWNER_ONLY)
    except FileExistsError:
        raise
    except OSError as err:
        raise _io_error(path, "cannot be created", err) from None
    try:
        with os.fdopen(fd, "w", encoding="ascii") as f:
            os.fchmod(fd, OWNER_ONLY)  # the umask may have taken the owner's bits too
            f.write(token + "\n")
            f.flush()
            os.fsync(fd)
    except OSError as err:
        with contextlib.suppress(OSError):
            path.unlink()
        raise _io_error(path, "cannot be written", err) from None


def _make_directory(path: Path) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise _io_error(path, f"cannot be created in {path.parent}", err) from None


def _unreadable(path: Path, err: OSError) -> TokenFileError:
    return TokenFileError(
        path, f"cannot be read ({err.strerror or err})", f"{ROTATE_HINT} (it replaces the file)"
    )


def _io_error(path: Path, problem: str, err: OSError | None) -> TokenFileError:
    why = f" ({err.strerror or err})" if err is not None else ""
    return TokenFileError(
        path,
        f"{problem}{why}",
        "make its directory writable by this user, or point --db / NEMESYS_DB_PATH elsewhere",
    )
