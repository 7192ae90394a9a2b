"""Atomic file output that never destroys what it should not.

Every writer of uasnav goes through :func:`atomic_open` (or :func:`atomic_write_bytes` /
:func:`atomic_write_text`). What happens depends on what the target path is:

- a regular file, or nothing yet: the data go to a temporary file beside the target, which is
  flushed, fsynced and renamed over the target (``os.replace``, atomic on POSIX and Windows).
  Readers never see a partial file; a failure leaves the target untouched. A new file gets
  ``0o666 & ~umask`` (not the 0600 of :func:`tempfile.mkstemp`); a replaced file keeps its
  permission bits (and, where we may, its owner).
- a symbolic link: written through to the file the link points to, atomically as above; the
  link itself is kept.
- a character device or a FIFO (``/dev/null``, ``/dev/stdout``, a named pipe): written
  directly, because replacing it would destroy the device node or the pipe.
- anything else (a directory, a socket, a block device …): refused with an
  :class:`~uasnav.errors.InputError` naming the path.

Missing parent directories of an output are created (``mkdir -p``); a run that fails removes
the directories it created. Errors of the operating system are re-raised with the *user's*
path, never the temporary file's.

Several files written by one run form a transaction with :func:`output_set`::

    with output_set() as out:
        out.write_bytes("a.png", png)
        write_log(log, "b.csv")          # any writer inside the block joins the set

Every file is staged as a temporary file first; only when the block ends without an exception
are they renamed into place, one after the other. If anything fails — the block, or any rename —
the replaced files are restored and the new ones removed: nothing of a failed run remains.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import errno
import os
import shutil
import stat
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from uasnav.errors import InputError

# The transaction that writers join, if a caller opened one (see output_set).
_ACTIVE: contextvars.ContextVar[OutputSet | None] = contextvars.ContextVar("uasnav_output_set", default=None)
_UMASK_LOCK = threading.Lock()
# Longest part of the target's name kept in a temporary file's name: the temporary name adds a
# prefix and suffix, and must stay below NAME_MAX (255) whenever the target's own name does.
_NAME_KEEP = 64


def current_umask() -> int:
    """The process umask (read without changing it where the OS allows)."""
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/self/status", encoding="ascii", errors="replace") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    # Portable fallback: os.umask can only be read by setting it; the lock keeps our own
    # threads from creating files in between.
    with _UMASK_LOCK:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def _user_oserror(exc: OSError, path: str) -> OSError:
    """``exc`` again, naming ``path`` (the user's path) instead of a temporary file's."""
    if exc.errno is None:
        return exc
    return OSError(exc.errno, exc.strerror or os.strerror(exc.errno), path)


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISBLK, "a block device"),
    ):
        if test(mode):
            return name
    return "not a regular file"


@dataclasses.dataclass
class _Staged:
    user: str  # the path as the user gave it (for messages)
    final: Path  # where the data end up (the symlink's target for a link)
    tmp: str  # the staged data
    direct: bool  # character device / FIFO: copy into it, no rename
    fd: int | None  # /dev/stdout and the like: the open descriptor written to
    existed: bool  # a regular file is replaced (restore it on rollback)
    key: tuple[Any, ...]  # identity of the target, to refuse writing one file twice


class OutputSet:
    """Files staged by one run, renamed into place together by :meth:`commit`.

    Use it through :func:`output_set`; the writers of uasnav (:func:`atomic_open` and all
    that call it) join the active set by themselves.
    """

    def __init__(self) -> None:
        self._staged: list[_Staged] = []
        self._created_dirs: list[Path] = []
        self._closed = False

    # ------------------------------------------------------------------ staging
    def _resolve(self, path: str | os.PathLike[str]) -> tuple[str, Path, bool, bool, tuple[Any, ...], int]:
        user = os.fspath(path)
        if not isinstance(user, str):
            user = os.fsdecode(user)
        if user == "":
            raise InputError("output path is empty")
        if user.endswith(("/", os.sep)):
            raise InputError(f"{user}: names a directory; give a file name")
        try:
            st: os.stat_result | None = os.stat(user)  # follows symbolic links
        except FileNotFoundError:
            st = None
        except OSError as e:  # ELOOP, EACCES, ENOTDIR …
            raise _user_oserror(e, user) from None
        if st is not None:
            if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode) or _open_descriptor(user) is not None:
                return user, Path(user), True, False, (st.st_dev, st.st_ino), 0
            if not stat.S_ISREG(st.st_mode):
                raise InputError(f"{user}: is {_kind(st.st_mode)}; refusing to write an output there")
        final = Path(os.path.realpath(user)) if os.path.islink(user) else Path(user)
        if st is not None:
            # keep the permission bits of the file we replace (but never hand set-id bits to
            # new contents)
            mode = stat.S_IMODE(st.st_mode) & ~(stat.S_ISUID | stat.S_ISGID)
            key: tuple[Any, ...] = (st.st_dev, st.st_ino)
        else:
            mode = 0o666 & ~current_umask()
            key = ("new", os.path.realpath(user))
        return user, final, False, st is not None, key, mode

    def _make_parents(self, directory: Path, user: str) -> None:
        missing: list[Path] = []
        d = directory
        while not d.exists() and d != d.parent:
            missing.append(d)
            d = d.parent
        for d in reversed(missing):
            try:
                d.mkdir()
            except FileExistsError:
                if not d.is_dir():
                    raise _user_oserror(OSError(errno.ENOTDIR, "Not a directory"), str(d)) from None
                continue
            except OSError as e:
                raise _user_oserror(e, str(d)) from None
            self._created_dirs.append(d)
        if not directory.is_dir():
            raise OSError(errno.ENOTDIR, f"Not a directory (parent of {user})", str(directory))

    @contextlib.contextmanager
    def open(self, path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
        """Stage ``path`` and yield a file handle for it (``mode`` ``"w"`` — UTF-8 text, no
        newline translation — or ``"wb"``)."""
        if mode not in ("w", "wb"):
            raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
        if self._closed:
            raise RuntimeError("output set already committed or rolled back")
        user, final, direct, existed, key, perm = self._resolve(path)
        for s in self._staged:
            if not direct and s.key == key:  # a device or pipe may take several outputs
                raise InputError(f"{user}: written twice by one run (also as {s.user})")
        if not direct:
            self._make_parents(final.parent, user)
        try:
            if direct:
                # stage outside the target's directory (a device lives in /dev); copied at commit
                fd, tmp = tempfile.mkstemp(prefix=".uasnav-out.", suffix=".tmp")
            else:
                fd, tmp = tempfile.mkstemp(
                    prefix=f".{final.name[:_NAME_KEEP]}.", suffix=".tmp", dir=final.parent
                )
        except OSError as e:
            raise _user_oserror(e, user) from None
        entry = _Staged(user, final, tmp, direct, _open_descriptor(user) if direct else None, existed, key)
        self._staged.append(entry)
        kwargs: dict[str, Any] = {"newline": "", "encoding": "utf-8"} if mode == "w" else {}
        try:
            with os.fdopen(fd, mode, **kwargs) as fh:
                if not direct and hasattr(os, "fchmod"):
                    os.fchmod(fh.fileno(), perm)
                    if existed:
                        _copy_owner(fh.fileno(), final)
                yield fh
                fh.flush()
                os.fsync(fh.fileno())
        except BaseException as exc:
            self._staged.remove(entry)
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            if isinstance(exc, OSError) and exc.filename in (None, tmp):  # e.g. ENOSPC on write
                raise _user_oserror(exc, user) from None
            raise

    def write_bytes(self, path: str | os.PathLike[str], data: bytes) -> None:
        """Stage ``data`` for ``path``."""
        with self.open(path, "wb") as fh:
            fh.write(data)

    def write_text(self, path: str | os.PathLike[str], text: str) -> None:
        """Stage ``text`` (UTF-8) for ``path``."""
        self.write_bytes(path, text.encode("utf-8"))

    # ----------------------------------------------------------- commit / undo
    def commit(self) -> None:
        """Rename every staged file into place, in the order staged; on any failure restore
        the replaced files, remove the new ones and re-raise."""
        if self._closed:
            raise RuntimeError("output set already committed or rolled back")
        self._closed = True
        done: list[tuple[_Staged, str | None]] = []
        current: _Staged | None = None
        try:
            for s in self._staged:
                if s.direct:
                    continue
                current = s
                backup = _backup(s.final) if s.existed and os.path.exists(s.final) else None
                try:
                    os.replace(s.tmp, s.final)
                except BaseException:
                    if backup is not None:
                        with contextlib.suppress(OSError):
                            os.unlink(backup)
                    raise
                done.append((s, backup))
            # Devices and pipes last: what is written there cannot be taken back.
            for s in self._staged:
                if s.direct:
                    current = s
                    if s.fd is not None:
                        for stream in (sys.stdout, sys.stderr):
                            with contextlib.suppress(Exception):
                                stream.flush()  # what the process printed comes first
                        dst = os.fdopen(os.dup(s.fd), "wb")
                    else:
                        dst = open(s.user, "wb")
                    with open(s.tmp, "rb") as src, dst:
                        shutil.copyfileobj(src, dst)
        except BaseException as exc:
            for s, backup in reversed(done):
                with contextlib.suppress(OSError):
                    if backup is not None:
                        os.replace(backup, s.final)
                    else:
                        os.unlink(s.final)
            self._discard()
            if isinstance(exc, OSError) and current is not None:
                raise _user_oserror(exc, current.user) from None
            raise
        for _s, backup in done:
            if backup is not None:
                with contextlib.suppress(OSError):
                    os.unlink(backup)
        for s in self._staged:
            if s.direct:
                with contextlib.suppress(OSError):
                    os.unlink(s.tmp)
        self._staged.clear()
        self._created_dirs.clear()

    def rollback(self) -> None:
        """Drop every staged file and the directories created for them; no target changes."""
        self._closed = True
        self._discard()

    def _discard(self) -> None:
        for s in self._staged:
            with contextlib.suppress(OSError):
                os.unlink(s.tmp)
        self._staged.clear()
        for d in reversed(self._created_dirs):
            with contextlib.suppress(OSError):  # not empty: something else put a file there
                d.rmdir()
        self._created_dirs.clear()

    @property
    def paths(self) -> list[str]:
        """The staged targets, as the user named them."""
        return [s.user for s in self._staged]


def _open_descriptor(path: str) -> int | None:
    """The descriptor ``path`` names, if it reaches its file through ``/proc/self/fd/N`` or
    ``/dev/fd/N`` (``/dev/stdout`` …): such an output is written to that open descriptor, at
    its offset, as a shell redirection expects (reopening the file would start at offset 0 and
    collide with what the process prints; replacing it would leave the descriptor writing to
    the old file)."""
    p = os.path.abspath(path)
    mine = ("/proc/self/fd/", f"/proc/{os.getpid()}/fd/", "/dev/fd/")
    for _ in range(40):
        for prefix in mine:
            if p.startswith(prefix) and p[len(prefix) :].isdigit():
                return int(p[len(prefix) :])
        if not os.path.islink(p):
            return None
        p = os.path.normpath(os.path.join(os.path.dirname(p), os.readlink(p)))
    return None


def _copy_owner(fd: int, original: Path) -> None:
    """Give the staged file the owner of the file it replaces, where we are allowed to."""
    with contextlib.suppress(OSError, AttributeError):
        st = os.stat(original)
        own = os.fstat(fd)
        if (st.st_uid, st.st_gid) != (own.st_uid, own.st_gid):
            os.fchown(fd, st.st_uid, st.st_gid)


def _backup(path: Path) -> str:
    """A second name for ``path``'s current contents (hard link; a copy where links fail)."""
    fd, name = tempfile.mkstemp(prefix=f".{path.name[:_NAME_KEEP]}.", suffix=".bak", dir=path.parent)
    os.close(fd)
    try:
        os.unlink(name)
        os.link(path, name)
    except OSError:
        shutil.copy2(path, name)
    return name


@contextlib.contextmanager
def output_set() -> Iterator[OutputSet]:
    """Stage every file written inside the block; commit them together at its end.

    Writers called inside the block (:func:`atomic_open`, :func:`uasnav.io.write_log`, model
    ``save`` methods, :func:`uasnav.plotting.save_png` …) join the set. On an exception in the
    block nothing is written; if a rename fails, the files already renamed are restored. A
    nested ``output_set`` joins the outer one.
    """
    outer = _ACTIVE.get()
    if outer is not None:
        yield outer
        return
    s = OutputSet()
    token = _ACTIVE.set(s)
    try:
        yield s
    except BaseException:
        s.rollback()
        raise
    finally:
        _ACTIVE.reset(token)
    s.commit()


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open ``path`` for writing atomically (``mode`` ``"w"``: UTF-8 text, or ``"wb"``).

    See the module's description for devices, links and directories. Inside
    :func:`output_set` the file is committed with the set; otherwise when the block ends.
    """
    with output_set() as s, s.open(path, mode) as fh:
        yield fh


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether ``a`` and ``b`` are one existing regular file (same device and inode, so hard
    links, symbolic links and other spellings of one path count)."""
    try:
        sa, sb = os.stat(a), os.stat(b)
    except (OSError, ValueError):
        return False
    return stat.S_ISREG(sa.st_mode) and (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino)


__all__ = [
    "OutputSet",
    "atomic_open",
    "atomic_write_bytes",
    "atomic_write_text",
    "current_umask",
    "output_set",
    "same_file",
]
