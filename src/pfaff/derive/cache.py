"""The on-disk cache of generated code: paid once per model, not once per process.

An entry is the generated source of a small system's fused kernel (:mod:`pfaff.derive.fused`) or
its machine code (SymEngine's LLVM backend), keyed by a hash of everything the equations are
derived from (each piece's kind, local form with its symbols' assumptions, coordinates and family
layout; the parameters in order; the versions of pfaff and SymEngine; the machine, since machine
code is specific to it).

Loading cached code runs it, so the cache trusts nothing it cannot check:

- the folder is ``$XDG_CACHE_HOME/pfaff`` (``~/.cache/pfaff`` when unset), made private (0700)
  to the user; a folder owned by another user, or one others may write to and that cannot be
  made private, is not used;
- an entry is read only through descriptors checked after opening (``O_NOFOLLOW``, ``fstat``):
  the folder actually opened is ours and writable by no one else, and so is the entry (one
  planted by another user while the folder was open to them is theirs, and ignored); a swap of
  the folder between a check and the read cannot make pfaff read another;
- every entry starts with the SHA-256 of the rest of the file and names its key; an entry whose
  hash or key does not match is ignored (and replaced by the next writer);
- entries are written to a temporary file in the folder and renamed into place, so a
  concurrent writer or a crash never leaves a half-written entry that could be read.

``PFAFF_CACHE=0`` turns the cache off.

Examples
--------
>>> import os, tempfile
>>> os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp()
>>> store("ab" * 32, "test", b"payload")
>>> load("ab" * 32, "test")
b'payload'
>>> oct(cache_dir().stat().st_mode & 0o777)
'0o700'
>>> del os.environ["XDG_CACHE_HOME"]
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import platform
import stat
from pathlib import Path

import symengine
import sympy as sp

FORMAT = 2  # the layout of an entry's payload; a change makes old entries unreachable


def cache_dir() -> Path | None:
    """The private cache folder, made if missing; None when the cache is off or unsafe."""
    if os.environ.get("PFAFF_CACHE", "1").strip() in ("0", "false", "no", "off"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = Path(base) / "pfaff"
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = path.lstat()
        if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid():
            return None  # a link, a file, or another user's folder: not ours to load code from
        if st.st_mode & 0o077:
            path.chmod(0o700)
    except OSError:
        return None
    return path


def model_key(eom: object) -> str | None:
    """The hash of what ``eom``'s equations are derived from, or None (no system to hash)."""
    system = getattr(eom, "system", None)
    if system is None:
        return None
    h = hashlib.sha256()
    for part in (
        f"pfaff-fused {FORMAT}",
        _version(),
        _generator_hash(),
        symengine.__version__,
        platform.machine(),
        platform.node(),
        repr(eom.n),
        repr(eom.m),
        sp.srepr(tuple(eom.parameters)),
    ):
        h.update(part.encode() + b"\0")
    for p in system.pieces:
        h.update(f"{p.kind}|{sp.srepr(p.key)}|{p.coords}|{p.template!r}".encode() + b"\0")
    return h.hexdigest()


@functools.cache
def _generator_hash() -> str:
    """The hash of the code that generates an entry: a changed generator never loads old code."""
    here = Path(__file__).parent
    h = hashlib.sha256()
    for name in (
        "cache",
        "engine",
        "fused",
        "fusedpower",
        "machine_kernel",
        "loopcode",
        "templates",
        "blocks",
        "equations",
    ):
        h.update((here / f"{name}.py").read_bytes())
    h.update((here.parent / "numeric" / "smallsolve.py").read_bytes())
    return h.hexdigest()


@functools.cache
def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pfaff")
    except PackageNotFoundError:  # pragma: no cover - run from a source tree
        return "source"


def _entry(folder: Path, key: str, kind: str) -> Path:
    return folder / f"{key}.{kind}"


def load(key: str, kind: str) -> bytes | None:
    """The payload stored under (key, kind), or None when absent, off, or failing its check.

    The checks are made on what is read, never on a path that could change in between: the
    folder is opened (not following a link) and checked through its descriptor (a folder of
    ours that no one else may write to), the entry is opened relative to that descriptor (not
    following a link) and checked through its own (a regular file of ours that no one else
    may write to), and only then read; a rename or a planted entry fails one of them.
    """
    folder = cache_dir()
    if folder is None:
        return None
    try:
        data = _read_private(folder, f"{key}.{kind}")
    except OSError:
        return None
    if data is None:
        return None
    head, sep, payload = data.partition(b"\n")
    if not sep:
        return None
    digest, _, named = head.decode("ascii", "replace").partition(" ")
    if named != f"{key}.{kind}" or hashlib.sha256(payload).hexdigest() != digest:
        return None
    return payload


def _private(st: os.stat_result, kind: int) -> bool:
    """Whether a status is of that kind, ours, and writable by no one else."""
    return stat.S_IFMT(st.st_mode) == kind and st.st_uid == os.getuid() and not st.st_mode & 0o022


def _read_private(folder: Path, name: str) -> bytes | None:
    """The bytes of ``folder/name`` if both are private (checked on the descriptors read)."""
    nofollow = getattr(os, "O_NOFOLLOW", 0)
    dfd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | nofollow)
    try:
        if not _private(os.fstat(dfd), stat.S_IFDIR):
            return None
        fd = os.open(name, os.O_RDONLY | nofollow, dir_fd=dfd)
        with os.fdopen(fd, "rb") as fh:
            if not _private(os.fstat(fh.fileno()), stat.S_IFREG):
                return None
            return fh.read()
    finally:
        os.close(dfd)


def store(key: str, kind: str, payload: bytes) -> None:
    """Write an entry atomically; any failure (a full disk, a read-only folder) is ignored."""
    folder = cache_dir()
    if folder is None:
        return
    head = f"{hashlib.sha256(payload).hexdigest()} {key}.{kind}\n".encode("ascii")
    tmp = folder / f".{key}.{kind}.{os.getpid()}.tmp"
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(head + payload)
        os.replace(tmp, _entry(folder, key, kind))
    except OSError:
        with contextlib.suppress(OSError):
            tmp.unlink()
