"""Atomic file output: write to a temporary file beside the target, then rename over it.

A failure half-way leaves the user's existing file untouched and no partial file behind. A target
that exists but is not a regular file (a device node such as /dev/null, a named pipe, a socket,
directly or through a link) is refused, never replaced. A target
that is a symbolic link is written through: the link's final target is replaced (in its own
folder, so the rename stays atomic) and the link is kept. An existing file keeps its permissions.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from pfaff.core.errors import OptionError


def file_path(path: object, name: str = "path") -> Path:
    """``path`` as a :class:`~pathlib.Path`, or an :class:`~pfaff.errors.OptionError` naming
    the argument when it is no file path (a number, None).

    Examples
    --------
    >>> file_path("run.csv")
    PosixPath('run.csv')
    >>> file_path(3)
    Traceback (most recent call last):
    pfaff.core.errors.OptionError: `path` must be a file path (str or os.PathLike); got int 3
    """
    text = os.fspath(path) if isinstance(path, str | os.PathLike) else None
    if not isinstance(text, str) or not text or "\x00" in text:
        raise OptionError(
            f"`{name}` must be a file path (str or os.PathLike); got "
            f"{type(path).__name__} {path!r:.80}"
        )
    return Path(text)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it to ``path`` on success.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("hello")
    >>> target.read_text()
    'hello'
    """
    target = file_path(path)
    if target.is_symlink():  # write where the link points, and keep the link
        target = Path(os.path.realpath(target))
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"cannot write `{path}`: folder `{folder}` does not exist")
    if target.is_dir():
        raise IsADirectoryError(f"cannot write `{path}`: it is a folder")
    kind = special_kind(target)
    if kind is not None:  # a rename would replace the device or pipe with a regular file
        raise FileExistsError(f"cannot write `{path}`: it is {kind}, not a regular file")
    mode = target.stat().st_mode & 0o7777 if target.exists() else None
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=suffix or target.suffix, dir=folder
    )
    os.close(fd)
    try:
        yield Path(tmp)
        if mode is None:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask  # mkstemp makes 0600; give a new file the usual permissions
        os.chmod(tmp, mode)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def read_capped(
    path: Path, max_bytes: int, what: str, error: type[Exception], hint: str = ""
) -> str:
    """The UTF-8 text of the regular file ``path``, at most ``max_bytes`` long, else ``error``.

    The size is checked before the file is read and again on what is read (a file that grows
    in between), a leading byte-order mark is dropped, and every failure names ``what``.

    Parameters
    ----------
    path : Path
        The file.
    max_bytes : int
        The cap on its size.
    what : str
        The file as messages name it, e.g. ``"the URDF file x.urdf"``.
    error : type
        The exception raised on any failure.
    hint : str
        Appended to the message of a file over the cap (how to raise it).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = p.write_bytes("\ufeffhello".encode())
    >>> read_capped(p, 100, f"file {p.name}", ValueError)
    'hello'
    >>> read_capped(p, 3, f"file {p.name}", ValueError)
    Traceback (most recent call last):
    ValueError: file a.txt: 8 bytes, above the cap of 3
    """
    try:
        size = path.stat().st_size
        if not path.is_file():
            raise error(f"{what}: not a regular file")
        if size > max_bytes:
            raise error(f"{what}: {size} bytes, above the cap of {max_bytes}{hint}")
        with path.open("rb") as fh:
            raw = fh.read(max_bytes + 1)
    except OSError as e:
        raise error(f"{what}: cannot be read ({e.strerror or e})") from None
    if len(raw) > max_bytes:
        raise error(f"{what}: larger than the cap of {max_bytes} bytes{hint}")
    try:
        return raw.decode("utf-8").removeprefix("\ufeff")  # a byte-order mark some editors write
    except UnicodeDecodeError as e:
        raise error(f"{what}: not UTF-8 text ({e.reason} at byte {e.start})") from None


def special_kind(target: Path) -> str | None:
    """What an existing target that is not a regular file is (a device, a pipe...), else None."""
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return None
    for test, kind in (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a named pipe"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return kind
    return None
