"""Paths from files people share: regular files only, bounded in size, confined to a folder.

A world file may name a picture to paint and a file to render to. Both are
taken relative to the world file's folder (as the user named it, a symlinked
world's link folder) and may not leave it: no absolute paths, no ``..`` out,
no symlink pointing out. Files are opened only when they are regular files,
so a world cannot make sandmod read ``/dev/zero``, block on a FIFO or write
over a device node. Every refusal is a :class:`Refused` with a message meant
for the user.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import BinaryIO

#: Largest mod or world file read (bytes); real ones are a few kilobytes.
MAX_TEXT_BYTES = 4 * 2**20
#: What :class:`Refused` says of a path where nothing is.
NO_SUCH_FILE = "no such file"


class Refused(ValueError):
    """A path or file that sandmod will not use; the message says why, for the user."""


def open_regular(path: str | Path) -> BinaryIO:
    """``path`` opened for reading in binary; Refused unless it is a regular file that can be read."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise Refused(_reason(exc)) from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise Refused("not a regular file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path: str | Path, limit: int = MAX_TEXT_BYTES) -> bytes:
    """The contents of the regular file ``path``; Refused if it is larger than ``limit`` bytes."""
    with open_regular(path) as file:
        data = file.read(limit + 1)
    if len(data) > limit:
        raise Refused(f"larger than {limit // 2**20} MB; not a file sandmod reads")
    return data


def inside(folder: Path, written: str, what: str = "path") -> Path:
    """``written`` (a path from a file) taken relative to ``folder``; Refused if it leaves ``folder``.

    Symlinks are followed before the check, so a link inside that points out
    is refused as well.
    """
    if PurePosixPath(written).is_absolute() or PureWindowsPath(written).is_absolute() or PureWindowsPath(written).drive:
        raise Refused(f"the {what} must be relative to the world file's folder (got an absolute path)")
    target = Path(folder) / written
    try:
        real, home = target.resolve(), Path(folder).resolve()
    except (OSError, RuntimeError):  # a symlink loop
        raise Refused(f"the {what} cannot be resolved (a symlink loop?)") from None
    if real != home and home not in real.parents:
        raise Refused(f"the {what} must lie inside the world file's folder")
    return target


def check_output(path: Path, *, folder: bool = False) -> None:
    """Refused if ``path`` exists as something a render must not replace: a device, FIFO or socket,
    a symlink, or a folder (a file, for a recorder that writes a folder)."""
    try:
        mode = os.lstat(path).st_mode
    except OSError:  # nothing there, or not reachable: writing it will say why
        return
    if stat.S_ISLNK(mode):
        raise Refused("is a symlink; give the path of the file itself")
    if folder and not stat.S_ISDIR(mode):
        raise Refused("exists and is not a folder")
    if not folder and not stat.S_ISREG(mode):
        raise Refused("exists and is not a regular file")


def _reason(exc: OSError) -> str:
    if exc.errno == errno.ELOOP:
        return "a symlink loop"
    if exc.errno == errno.ENOENT:
        return NO_SUCH_FILE
    return exc.strerror or str(exc)
