"""The operator token kept beside the mission log (issue 19, item 6): made owner-only (0600)
in one step, reused by the next start (``create_app`` and ``nemesys console`` alike),
replaced by ``--new-token``; an explicit token wins; a token file that is open to others,
belongs to another user, is a link or holds no token stops the start with a line naming the
file and the fix (exit 2), never a new token in its place."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.settings import Settings
from backend.token_file import TOKEN_FORM, TokenFileError, token_path, with_kept_token
from bench._server import REPO, free_port, start_console

from .conftest import TIME_SCALE, clear_nemesys_env

RUN_TIMEOUT_S = 60.0


@pytest.fixture(autouse=True)
def _no_env(monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)  # a NEMESYS_TOKEN of the shell would make it explicit


def settings(db: Path, **overrides: Any) -> Settings:
    """Settings without a token: the kept one is used."""
    values: dict[str, Any] = {
        "db_path": db,
        "viewer_port": 0,
        "sim_time_scale": TIME_SCALE,
        "allowed_hosts": ["testserver"],
    }
    return Settings(**(values | overrides))


def mode_of(path: Path) -> int:
    return stat.S_IMODE(path.lstat().st_mode)


def kept(path: Path) -> str:
    return path.read_text(encoding="ascii").removesuffix("\n")


# --- the file ---------------------------------------------------------------------------


def test_the_token_is_made_owner_only_and_reused(tmp_path: Path) -> None:
    db = tmp_path / "log" / "missions.sqlite3"  # the directory is made too
    first = with_kept_token(settings(db)).token
    path = token_path(db)
    assert path == tmp_path / "log" / "missions.sqlite3.token"
    assert mode_of(path) == 0o600
    assert TOKEN_FORM.fullmatch(first) and kept(path) == first
    assert with_kept_token(settings(db)).token == first
    assert with_kept_token(settings(db)).token == first  # not a new one per read either


def test_the_file_is_never_open_to_others_not_even_at_its_creation(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The file that holds the token is created by one ``open`` with ``O_EXCL`` and mode 0600
    (no chmod afterwards that would leave a moment open to others), with no umask's help."""
    calls: list[tuple[str, int, int]] = []
    real_open = os.open

    def spy(path: Any, flags: int, mode: int = 0o777, *args: Any, **kwargs: Any) -> int:
        calls.append((str(path), flags, mode))
        return real_open(path, flags, mode, *args, **kwargs)

    monkeypatch.setattr(os, "open", spy)
    old_umask = os.umask(0)  # the mode alone must keep the group and others out
    try:
        db = tmp_path / "missions.sqlite3"
        with_kept_token(settings(db))
        with_kept_token(settings(db), rotate=True)
    finally:
        os.umask(old_umask)
    created = [(p, flags, mode) for p, flags, mode in calls if flags & os.O_CREAT]
    assert len(created) == 2, calls  # the first token, then the replacement's new file
    for _path, flags, mode in created:
        assert flags & os.O_EXCL and flags & os.O_NOFOLLOW
        assert mode == 0o600
    assert mode_of(token_path(tmp_path / "missions.sqlite3")) == 0o600
    assert [p.name for p in tmp_path.iterdir()] == ["missions.sqlite3.token"]  # no leftover


def test_new_token_replaces_the_kept_one(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    old = with_kept_token(settings(db)).token
    new = with_kept_token(settings(db), rotate=True).token
    assert new != old and TOKEN_FORM.fullmatch(new)
    assert kept(token_path(db)) == new and mode_of(token_path(db)) == 0o600
    assert with_kept_token(settings(db)).token == new


def test_an_explicit_token_wins_and_no_file_is_made(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    with_kept_token(settings(db))
    assert with_kept_token(settings(db, token="e" * 20)).token == "e" * 20
    other = tmp_path / "other.sqlite3"
    with_kept_token(settings(other, token="e" * 20))
    assert not token_path(other).exists()
    with pytest.raises(TokenFileError, match="set explicitly"):
        with_kept_token(settings(other, token="e" * 20), rotate=True)


def test_an_in_memory_log_gets_a_token_per_start(tmp_path: Path) -> None:
    memory = settings(Path(":memory:"))
    assert with_kept_token(memory).token != with_kept_token(memory).token
    assert list(tmp_path.iterdir()) == []


def _chmod(mode: int) -> Callable[[Path], None]:
    def spoil(path: Path) -> None:
        path.chmod(mode)

    return spoil


def _write(data: bytes) -> Callable[[Path], None]:
    def spoil(path: Path) -> None:
        path.write_bytes(data)

    return spoil


def _link(path: Path) -> None:
    target = path.with_name("elsewhere")
    path.rename(target)
    path.symlink_to(target)


def _directory(path: Path) -> None:
    path.unlink()
    path.mkdir()


@pytest.mark.parametrize(
    ("spoil", "words"),
    [
        (_chmod(0o644), ("mode 0644", "may have been read", "--new-token", "chmod 600")),
        (_chmod(0o640), ("mode 0640", "--new-token")),
        (_chmod(0o602), ("mode 0602", "--new-token")),
        (_write(b""), ("holds no operator token", "--new-token")),
        (_write(b"short\n"), ("holds no operator token", "16 to 256")),
        (_write(b"with space in the token\n"), ("holds no operator token",)),
        (_write("\u00e9".encode() * 20), ("holds no operator token",)),
        (_write(b"a" * 5000), ("holds no operator token",)),
        (_link, ("is a symbolic link", "--new-token")),
        (_directory, ("is not a regular file", "--new-token")),
    ],
    ids=[
        "world-readable",
        "group-readable",
        "world-writable",
        "empty",
        "too-short",
        "spaces",
        "not-ascii",
        "too-long",
        "symlink",
        "directory",
    ],
)
def test_an_unsafe_or_unreadable_file_is_a_clear_error_never_a_new_token(
    tmp_path: Path, spoil: Callable[[Path], None], words: tuple[str, ...]
) -> None:
    db = tmp_path / "missions.sqlite3"
    with_kept_token(settings(db))
    path = token_path(db)
    spoil(path)
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(TokenFileError) as caught:
        with_kept_token(settings(db))
    message = str(caught.value)
    assert message.startswith(f"operator token file {path} "), message
    for word in words:
        assert word in message, message
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing made or replaced
    # the fix named works: a new token, owner-only (a directory is removed first, as said)
    if path.is_dir() and not path.is_symlink():
        path.rmdir()
    token = with_kept_token(settings(db), rotate=True).token
    assert kept(path) == token and mode_of(path) == 0o600 and not path.is_symlink()


def test_a_file_of_another_user_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    db = tmp_path / "missions.sqlite3"
    with_kept_token(settings(db))
    someone_else = os.getuid() + 1
    monkeypatch.setattr(os, "getuid", lambda: someone_else)
    with pytest.raises(TokenFileError, match=r"belongs to another user \(uid \d+\)"):
        with_kept_token(settings(db))


# --- the app and the console command ------------------------------------------------------


def test_two_app_starts_share_the_kept_token(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    with TestClient(create_app(settings(db), viewer=False)) as client:
        token = kept(token_path(db))
        session = client.get("/api/session", headers={"Authorization": f"Bearer {token}"})
        assert session.json()["authenticated"] is True
    again = create_app(settings(db), viewer=False)
    assert again.state.settings.token == token


def run_console(db: Path, *extra: str, env: dict[str, str] | None = None) -> str:
    """``nemesys console`` that must refuse to start: its one stderr line (exit 2, no URL)."""
    child_env = {k: v for k, v in os.environ.items() if not k.startswith("NEMESYS_")}
    child_env.update(env or {})
    args = ["console", "--db", str(db), "--port", str(free_port()), "--viewer-port", "0"]
    result = subprocess.run(
        [sys.executable, "-m", "cli.main", *args, *extra],
        cwd=REPO,
        env=child_env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert "?token=" not in output and "Traceback" not in output, output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("nemesys console: "), output
    return lines[0]


@pytest.mark.slow  # three real `nemesys console` processes
def test_console_restarts_keep_the_token_and_new_token_replaces_it(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    path = token_path(db)
    tokens = []
    for n, extra in enumerate(((), (), ("--new-token",))):
        with start_console(tmp_path / f"console-{n}.log", None, "--db", str(db), *extra) as c:
            tokens.append(c.token)
            assert kept(path) == c.token and mode_of(path) == 0o600
            printed = c.log_tail(40)
            if extra:
                assert "New operator token" in printed, printed
            else:
                assert f"the token is kept in {path}" in printed, printed
            with c.client() as http:
                auth = {"Authorization": f"Bearer {c.token}"}
                assert http.get("/api/session", headers=auth).json()["authenticated"] is True
    assert tokens[0] == tokens[1] != tokens[2]

    path.chmod(0o644)
    line = run_console(db)
    assert f"operator token file {path} is open to other users (mode 0644" in line, line
    assert "--new-token" in line
    assert kept(path) == tokens[2]  # left as it was, for the operator to fix
    line = run_console(db, "--new-token", env={"NEMESYS_TOKEN": "e" * 20})
    assert "set explicitly" in line and "NEMESYS_TOKEN" in line, line
