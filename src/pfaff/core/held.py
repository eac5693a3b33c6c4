"""``signals_held``: SIGINT and SIGTERM held while a block runs, then delivered.

numba's import and the load of its on-disk cache can swallow a Ctrl-C (seen under load: a long
run that Ctrl-C did not end); every place that loads numba code does it inside this block, so
the signal reaches the handler it was meant for once the code is loaded.

Examples
--------
>>> with signals_held():
...     x = 1 + 1
>>> x
2
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM held while the block runs, then delivered to the handlers they had
    (each kind once). Outside the main thread, nothing is held (signals are the main
    thread's)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    held = (signal.SIGINT, signal.SIGTERM)
    old = {s: signal.signal(s, lambda signum, _frame: caught.append(signum)) for s in held}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(caught):
            signal.raise_signal(s)
