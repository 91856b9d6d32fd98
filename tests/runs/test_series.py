"""The experiments' one loop (copi.runs._series.execute): Ctrl-C stops it even when the
KeyboardInterrupt it raised is swallowed by the code that was running."""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import nullcontext

import pytest

from copi.runs._executor import InlineExecutor
from copi.runs._series import ctrl_c_remembered, execute


@pytest.fixture
def default_ctrl_c() -> Iterator[None]:
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def _swallowing(at: int):  # an item that eats the Ctrl-C pressed while it runs
    def one(config: object, item: int) -> list[int]:
        if item == at:
            try:
                signal.raise_signal(signal.SIGINT)
            except KeyboardInterrupt:
                pass
        return [item]

    return one


def test_a_swallowed_ctrl_c_still_stops_the_loop_at_the_next_item(default_ctrl_c) -> None:
    done: list[int] = []
    with pytest.raises(KeyboardInterrupt):
        execute(None, list(range(50)), one=_swallowing(3), many=lambda c, xs: xs,
                commit=done.extend, pool=InlineExecutor(), workers=1, chunk=1,
                stopping=nullcontext())  # fmt: skip
    assert done == [0, 1, 2, 3]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_run_without_ctrl_c_runs_every_item_and_leaves_the_handler(default_ctrl_c) -> None:
    done: list[int] = []
    execute(None, list(range(20)), one=lambda c, x: [x], many=lambda c, xs: xs,
            commit=done.extend, pool=InlineExecutor(), workers=1, chunk=1,
            stopping=nullcontext())  # fmt: skip
    assert done == list(range(20))
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_ignored_or_own_ctrl_c_handler_is_left_alone() -> None:
    def own(signum: int, frame: object) -> None:
        pass

    for handler in (signal.SIG_IGN, own):
        before = signal.signal(signal.SIGINT, handler)
        try:
            with ctrl_c_remembered() as pressed:
                assert signal.getsignal(signal.SIGINT) is handler
                signal.raise_signal(signal.SIGINT)
                assert not pressed()
            assert signal.getsignal(signal.SIGINT) is handler
        finally:
            signal.signal(signal.SIGINT, before)


def test_the_ctrl_c_behind_an_error_is_found_through_its_chain_and_a_loop_ends() -> None:
    from copi.errors import ctrl_c_behind

    pressed = KeyboardInterrupt()
    numba = SystemError("returned a result with an exception set")
    numba.__context__ = pressed
    outer = RuntimeError("wrapped")
    outer.__cause__ = numba
    assert ctrl_c_behind(outer) is pressed and ctrl_c_behind(pressed) is pressed
    a, b = ValueError("a"), SystemError("b")
    a.__context__, b.__context__ = b, a  # a chain that loops: no Ctrl-C in it
    assert ctrl_c_behind(a) is None
