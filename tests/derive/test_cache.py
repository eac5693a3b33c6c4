"""The on-disk cache of generated code (:mod:`pfaff.derive.cache`)."""

from __future__ import annotations

import os
import stat
import threading

import numpy as np
import pytest

import pfaff
from pfaff.derive import cache

VALUES = {"m": 1.3, "g": 9.81, "L": 0.7}


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("PFAFF_CACHE", raising=False)
    return tmp_path / "pfaff"


def _compiled(evaluator=None):
    return pfaff.models.cartesian_pendulum().equations().compile(VALUES, evaluator=evaluator)


def _state():
    return 0.0, np.array([0.7 * np.sin(0.4), -0.7 * np.cos(0.4)]), np.zeros(2)


def test_second_compile_is_a_hit_with_the_same_numbers(folder) -> None:
    first = _compiled()
    assert first.timings["cache"] == "miss"
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    entries = sorted(p.suffix for p in folder.iterdir())
    assert entries == [".code"]
    second = _compiled()  # a new derivation of the same system
    assert second.timings["cache"] == "hit"
    a, b = first.accelerations(*_state()), second.accelerations(*_state())
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    # pendulum: the rod tension -2Lλ at rest, hanging at angle 0.4, is m g cos 0.4
    assert -2 * 0.7 * a[1][0] == pytest.approx(1.3 * 9.81 * np.cos(0.4), rel=1e-12)
    assert {"equations", "compile", "codegen"} <= set(second.timings)


def test_machine_code_is_cached_and_agrees(folder) -> None:
    model = _compiled("machine")
    tr = pfaff.simulate(model, *_state()[1:], (0.0, 0.5))
    if not any(p.suffix == ".llvm" for p in folder.iterdir()):
        pytest.skip("SymEngine has no LLVM backend here")
    again = pfaff.simulate(_compiled("machine"), *_state()[1:], (0.0, 0.5))
    np.testing.assert_allclose(again.q[-1], tr.q[-1], rtol=0, atol=1e-13)


def test_a_tampered_entry_is_ignored_and_replaced(folder) -> None:
    _compiled()
    (entry,) = folder.iterdir()
    data = bytearray(entry.read_bytes())
    data[-5] ^= 0x01  # one bit of the generated source
    entry.write_bytes(bytes(data))
    model = _compiled()
    assert model.timings["cache"] == "miss"
    assert model.accelerations(*_state())[1][0] == pytest.approx(
        -1.3 * 9.81 * np.cos(0.4) / (2 * 0.7), rel=1e-12
    )
    assert _compiled().timings["cache"] == "hit"  # the next writer replaced it


def test_an_entry_under_another_name_is_ignored(folder) -> None:
    cache.store("a" * 64, "code", b"print('hi')")
    os.replace(folder / ("a" * 64 + ".code"), folder / ("b" * 64 + ".code"))
    assert cache.load("b" * 64, "code") is None
    assert cache.load("a" * 64, "code") is None


def test_off_and_private(folder, monkeypatch) -> None:
    monkeypatch.setenv("PFAFF_CACHE", "0")
    assert _compiled().timings["cache"] == "off"
    assert not folder.exists()
    monkeypatch.delenv("PFAFF_CACHE")
    folder.mkdir(mode=0o777)
    folder.chmod(0o777)
    assert cache.cache_dir() == folder
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700


def test_a_link_is_not_used(folder, tmp_path) -> None:
    other = tmp_path / "elsewhere"
    other.mkdir(mode=0o700)
    folder.symlink_to(other)
    assert cache.cache_dir() is None
    _compiled()
    assert list(other.iterdir()) == []


def test_concurrent_writers_never_show_a_partial_entry(folder) -> None:
    payloads = [bytes([i]) * 200_000 for i in range(1, 5)]
    seen: list = []

    def write(p: bytes) -> None:
        for _ in range(20):
            cache.store("c" * 64, "code", p)
            seen.append(cache.load("c" * 64, "code"))

    threads = [threading.Thread(target=write, args=(p,)) for p in payloads]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert all(s in payloads for s in seen if s is not None)
    assert cache.load("c" * 64, "code") in payloads


def _plant(where, key: str, kind: str, payload: bytes):
    """A well-formed entry (right hash, right name) with a payload of someone else's."""
    head = f"{cache.hashlib.sha256(payload).hexdigest()} {key}.{kind}\n".encode()
    path = where / f"{key}.{kind}"
    path.write_bytes(head + payload)
    return path


def test_an_entry_others_may_write_is_never_loaded(folder) -> None:
    """A well-formed entry that group or others may write (planted while the folder was open
    to them) is ignored: checked on the opened file's own status."""
    key = "cd" * 32
    cache.store(key, "code", b"ours")
    assert cache.load(key, "code") == b"ours"
    planted = _plant(folder, key, "code", b"theirs")
    planted.chmod(0o666)
    assert cache.load(key, "code") is None
    planted.chmod(0o600)
    assert cache.load(key, "code") == b"theirs"  # (the same bytes, once private: the check)


@pytest.mark.skipif(os.geteuid() != 0, reason="making a file of another user needs root")
def test_an_entry_of_another_user_is_never_loaded(folder) -> None:
    key = "ce" * 32
    cache.store(key, "code", b"ours")
    planted = _plant(folder, key, "code", b"theirs")
    os.chown(planted, 65534, 65534)
    planted.chmod(0o600)
    assert cache.load(key, "code") is None


def test_a_linked_entry_is_not_followed(folder, tmp_path) -> None:
    key = "cf" * 32
    cache.store(key, "code", b"ours")
    outside = tmp_path / "outside"
    outside.mkdir()
    target = _plant(outside, key, "code", b"theirs")
    (folder / f"{key}.code").unlink()
    (folder / f"{key}.code").symlink_to(target)
    assert cache.load(key, "code") is None


@pytest.mark.parametrize("swap", ["link", "folder"])
def test_a_folder_swapped_after_its_check_is_not_read(folder, tmp_path, monkeypatch, swap) -> None:
    """The rename race: the folder passes cache_dir's check, then is swapped (for a link to,
    or for, a folder others may write to, holding a well-formed entry) before the read."""
    key = "d0" * 32
    cache.store(key, "code", b"ours")
    hostile = tmp_path / "hostile"
    hostile.mkdir()
    _plant(hostile, key, "code", b"theirs").chmod(0o600)
    hostile.chmod(0o777)
    checked = cache.cache_dir

    def check_then_swap():
        path = checked()
        path.rename(tmp_path / "moved")
        if swap == "link":
            path.symlink_to(hostile)
        else:
            hostile.rename(path)
        return path

    monkeypatch.setattr(cache, "cache_dir", check_then_swap)
    assert cache.load(key, "code") is None
