"""netCDF files written one record at a time, and read back as memory maps: :class:`RecordWriter`.

A run's states are appended to a netCDF file as they are reported, so that a run of 2^24
particles keeps none of them in memory. The file is netCDF's classic 64-bit-offset format
(CDF-2: what ``scipy.io.netcdf_file``, xarray's ``scipy`` engine and every netCDF library read),
written here directly, because it is the format built for this: the record dimension (``time``)
is unlimited and each record, every per-state variable of one reported time side by side, goes at
the end of the file, after which the record count in the header is rewritten. SciPy's own writer
keeps every variable in memory until the file is closed. A record of one variable may hold up to
4 GiB (2^29 numbers, q of 2^29 coordinates); the file as a whole has no limit.

The header is written with room to spare, so the global attributes (the run's status, message
and statistics, known only at the end) are rewritten in place when the file is finished. Until
then the record count in the header counts only complete records: a file cut short (the process
killed) still reads as the records it had.

:func:`read_variables` maps a file back: every variable an array over the file (``np.memmap``,
read-only, big-endian as stored), the record variables strided views of the records. Nothing is
read until it is used.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from pathlib import Path

import numpy as np

MAGIC = b"CDF\x02"  # classic format, 64-bit offsets
_DIM, _VAR, _ATT = 10, 11, 12
_TYPES = {1: ">i1", 2: "S1", 3: ">i2", 4: ">i4", 5: ">f4", 6: ">f8"}  # nc_type -> dtype
_CODES = {"f": 6, "i": 4, "S": 2}
HEADER_ROOM = 1 << 18  # bytes reserved after the header for the final attributes
CHUNK = 1 << 20  # numbers byte-swapped per write (bounded scratch memory)


def _pad(b: bytes) -> bytes:
    return b + b"\0" * (-len(b) % 4)


def _name(s: str) -> bytes:
    raw = s.encode("utf-8")
    return struct.pack(">i", len(raw)) + _pad(raw)


def _attr(name: str, value: object) -> bytes:
    if isinstance(value, str):
        raw = value.encode("utf-8")
        return _name(name) + struct.pack(">ii", 2, len(raw)) + _pad(raw)
    arr = np.atleast_1d(np.asarray(value))
    if arr.dtype.kind in "iub" and np.all(np.abs(arr.astype(np.int64)) < 2**31):
        arr = arr.astype(">i4")
        code = 4
    else:
        arr = arr.astype(">f8")
        code = 6
    return _name(name) + struct.pack(">ii", code, arr.size) + _pad(arr.tobytes())


def _attrs(attrs: dict) -> bytes:
    if not attrs:
        return b"\0" * 8
    return struct.pack(">ii", _ATT, len(attrs)) + b"".join(_attr(k, v) for k, v in attrs.items())


class _Var:
    """One variable: its name, dimensions, dtype, attributes and place in the file."""

    def __init__(self, name: str, dims: tuple[str, ...], shape: tuple[int, ...], dtype: str,
                 attrs: dict | None = None, data: np.ndarray | None = None) -> None:  # fmt: skip
        self.name, self.dims, self.shape, self.dtype = name, dims, shape, np.dtype(dtype)
        self.attrs, self.data = dict(attrs or {}), data
        self.record = bool(dims) and dims[0] == "time"
        self.size = int(np.prod(shape, dtype=np.int64)) * self.dtype.itemsize  # one record's
        self.vsize = self.size + (-self.size % 4)
        self.begin = 0


class RecordWriter:
    """A netCDF (CDF-2) file written one record (one reported time) at a time.

    Parameters
    ----------
    path : path-like
        The file (created or truncated).
    dims : dict of str to int
        The fixed dimensions and their sizes (> 0); ``time`` is the record dimension.
    variables : sequence of (name, dims, dtype) or (name, dims, dtype, data)
        ``dims`` a tuple of dimension names; a record variable's first is ``time``. ``dtype``
        "f8", "i4" or "S1" (characters); ``data``: a fixed variable's values, written at once.
    attrs : dict
        Global attributes (str, numbers or arrays of numbers); :meth:`finish` rewrites them.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "run.nc"
    >>> w = RecordWriter(path, {"coordinate": 2}, [("time", ("time",), "f8"),
    ...                  ("q", ("time", "coordinate"), "f8")], {"status": "running"})
    >>> for t in (0.0, 0.5):
    ...     w.append({"time": t, "q": [t, 2 * t]})
    >>> w.finish({"status": "success"})
    >>> v, attrs = read_variables(path)
    >>> v["q"].tolist(), attrs["status"]
    ([[0.0, 0.0], [0.5, 1.0]], 'success')
    """

    def __init__(self, path: str | os.PathLike, dims: dict[str, int], variables: Sequence[tuple],
                 attrs: dict) -> None:  # fmt: skip
        self.path, self.dims = Path(path), {"time": 0, **dims}
        names = list(self.dims)
        self.vars = []
        for spec in variables:
            name, vdims, dtype = spec[:3]
            shape = tuple(self.dims[d] for d in vdims if d != "time")
            data = spec[3] if len(spec) > 3 else None
            attrs_v = {"_Encoding": "utf-8"} if dtype == "S1" else None  # (xarray decodes)
            self.vars.append(_Var(name, vdims, shape, dtype, attrs_v, data))
        self._dimids = {d: names.index(d) for d in names}
        self.records = 0
        self._room = len(self._header(attrs)) + HEADER_ROOM
        offset = self._room
        for v in self.vars:
            if not v.record:
                v.begin, offset = offset, offset + v.vsize
        self._recsize = 0
        for v in self.vars:
            if v.record:
                v.begin, self._recsize = offset + self._recsize, self._recsize + v.vsize
        self._start = offset
        self._fh = open(self.path, "wb")
        self._write_header(attrs)
        for v in self.vars:
            if not v.record:
                self._fh.seek(v.begin)
                self._fh.write(
                    _pad(np.ascontiguousarray(v.data, dtype=v.dtype.newbyteorder(">")).tobytes())
                )
        self._fh.seek(self._start)

    def _header(self, attrs: dict) -> bytes:
        out = [MAGIC, struct.pack(">i", self.records)]
        out.append(struct.pack(">ii", _DIM, len(self.dims)))
        out += [_name(d) + struct.pack(">i", n) for d, n in self.dims.items()]
        out.append(_attrs(attrs))
        out.append(struct.pack(">ii", _VAR, len(self.vars)))
        for v in self.vars:
            ids = struct.pack(f">{len(v.dims)}i", *(self._dimids[d] for d in v.dims))
            vsize = min(v.vsize, 2**32 - 1)
            out.append(_name(v.name) + struct.pack(">i", len(v.dims)) + ids + _attrs(v.attrs))
            out.append(struct.pack(">iIq", _CODES[v.dtype.kind], vsize, v.begin))
        return b"".join(out)

    def _write_header(self, attrs: dict) -> None:
        head = self._header(attrs)
        if len(head) > self._room:
            raise ValueError("the attributes outgrew the room reserved for the header")
        self._fh.seek(0)
        self._fh.write(head)

    def append(self, values: dict[str, object]) -> None:
        """Write one record (every record variable's values at one time), then count it."""
        fh = self._fh
        fh.seek(self._start + self.records * self._recsize)
        for v in self.vars:
            if not v.record:
                continue
            a = np.asarray(values[v.name], dtype=v.dtype).reshape(-1)
            if a.size * v.dtype.itemsize != v.size:
                raise ValueError(f"record of `{v.name}`: {a.size} values for shape {v.shape}")
            big = v.dtype.newbyteorder(">")
            for i in range(0, a.size, CHUNK):
                fh.write(a[i : i + CHUNK].astype(big))
            fh.write(b"\0" * (v.vsize - v.size))
        fh.flush()
        self.records += 1
        fh.seek(4)
        fh.write(struct.pack(">i", self.records))

    def finish(self, attrs: dict) -> None:
        """Rewrite the header with the final attributes and close the file (records past the
        counted ones, a write cut short, are cut off)."""
        self._fh.truncate(self._start + self.records * self._recsize)
        self._write_header(attrs)
        self._fh.close()

    def close(self) -> None:
        """Close without finishing (the file is then removed by its owner)."""
        self._fh.close()


def _read_name(buf: memoryview, pos: int) -> tuple[str, int]:
    (n,) = struct.unpack_from(">i", buf, pos)
    pos += 4
    return bytes(buf[pos : pos + n]).decode("utf-8"), pos + n + (-n % 4)


def _read_attrs(buf: memoryview, pos: int) -> tuple[dict, int]:
    tag, count = struct.unpack_from(">ii", buf, pos)
    pos, out = pos + 8, {}
    for _ in range(count if tag == _ATT else 0):
        name, pos = _read_name(buf, pos)
        code, n = struct.unpack_from(">ii", buf, pos)
        pos += 8
        dt = np.dtype(_TYPES[code])
        raw = bytes(buf[pos : pos + n * dt.itemsize])
        pos += n * dt.itemsize + (-(n * dt.itemsize) % 4)
        if code == 2:
            out[name] = raw.decode("utf-8")
        else:
            vals = np.frombuffer(raw, dt).astype(dt.newbyteorder("="))
            out[name] = vals[0].item() if n == 1 else vals
    return out, pos


def read_variables(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict]:
    """The variables of a classic or 64-bit-offset netCDF file as memory maps, and its global
    attributes. Character variables come back decoded as arrays of str (they are small)."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 20)
        size = os.fstat(fh.fileno()).st_size
    if head[:3] != b"CDF" or head[3] not in (1, 2):
        raise ValueError(f"`{path}` is not a classic netCDF file")
    buf, wide = memoryview(head), head[3] == 2
    (numrecs,) = struct.unpack_from(">i", buf, 4)
    tag, ndims = struct.unpack_from(">ii", buf, 8)
    pos, dims = 16, []
    for _ in range(ndims if tag == _DIM else 0):
        name, pos = _read_name(buf, pos)
        dims.append((name, struct.unpack_from(">i", buf, pos)[0]))
        pos += 4
    attrs, pos = _read_attrs(buf, pos)
    tag, nvars = struct.unpack_from(">ii", buf, pos)
    pos, specs = pos + 8, []
    for _ in range(nvars if tag == _VAR else 0):
        name, pos = _read_name(buf, pos)
        (nd,) = struct.unpack_from(">i", buf, pos)
        ids = struct.unpack_from(f">{nd}i", buf, pos + 4)
        _, pos = _read_attrs(buf, pos + 4 + 4 * nd)
        code, vsize = struct.unpack_from(">iI", buf, pos)
        begin = struct.unpack_from(">q" if wide else ">I", buf, pos + 8)[0]
        pos += 16 if wide else 12
        specs.append((name, [dims[i] for i in ids], np.dtype(_TYPES[code]), vsize, begin))
    records = [s for s in specs if s[1] and s[1][0][1] == 0]
    recsize = (
        sum(s[3] for s in records)
        if len(records) > 1
        else sum(int(np.prod([d[1] for d in s[1][1:]])) * s[2].itemsize for s in records)
    )
    numrecs = min(numrecs, (size - records[0][4]) // recsize if records and recsize else 0)
    out = {}
    for name, vdims, dt, _vsize, begin in specs:
        shape = (
            tuple(n for d, n in vdims if n)
            if vdims and vdims[0][1] == 0
            else tuple(n for _, n in vdims)
        )
        if vdims and vdims[0][1] == 0:
            out[name] = _record_view(path, begin, numrecs, recsize, dt, shape)
        else:
            count = int(np.prod(shape, dtype=np.int64))
            arr = np.memmap(path, dt, "r", begin, (count,)) if count else np.empty(0, dt)
            out[name] = arr.reshape(shape)
        if dt.kind == "S":
            out[name] = _strings(np.asarray(out[name]))
    return out, attrs


def _record_view(path, begin: int, k: int, recsize: int, dt: np.dtype, shape: tuple) -> np.ndarray:
    """A record variable over the file: shape (k, *shape), strided by the record size."""
    count = int(np.prod(shape, dtype=np.int64))
    if k == 0 or count == 0:
        return np.empty((k, *shape), dt)
    raw = np.memmap(path, np.uint8, "r", begin, ((k - 1) * recsize + count * dt.itemsize,))
    inner = tuple(int(np.prod(shape[i + 1 :], dtype=np.int64)) * dt.itemsize
                  for i in range(len(shape)))  # fmt: skip
    return np.ndarray((k, *shape), dt, buffer=raw, strides=(recsize, *inner))


def _strings(chars: np.ndarray) -> np.ndarray:
    """Character arrays (…, width) as str (…), UTF-8, trailing NULs dropped."""
    if chars.ndim == 0:
        return chars
    flat = chars.reshape(-1, chars.shape[-1]) if chars.shape[-1] else chars.reshape(-1, 0)
    words = [b"".join(row.tolist()).rstrip(b"\0").decode("utf-8") for row in flat]
    return np.array(words, dtype=str).reshape(chars.shape[:-1])


def char_array(words: Sequence[str]) -> np.ndarray:
    """Strings as a netCDF character array, shape (len(words), width) of UTF-8 bytes.

    Examples
    --------
    >>> char_array(["x", "θ_1"]).shape
    (2, 4)
    """
    raw = [w.encode("utf-8") for w in words]
    width = max((len(r) for r in raw), default=1) or 1
    return (
        np.array([r.ljust(width, b"\0") for r in raw], dtype=f"S{width}")
        .view("S1")
        .reshape(len(raw), width)
    )
