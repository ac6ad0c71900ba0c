"""Bad input raises pacs.Error subclasses (ValueError / TypeError) naming the argument and
value; nothing crashes the interpreter."""

import numpy as np
import pytest

import pacs


@pytest.fixture
def shield(demo):
    s = pacs.Shield()
    s.start(0.0, demo.start)
    return s


def test_error_hierarchy():
    assert issubclass(pacs.InputError, pacs.Error) and issubclass(pacs.InputError, ValueError)
    assert issubclass(pacs.ArgumentTypeError, pacs.Error)
    assert issubclass(pacs.ArgumentTypeError, TypeError)
    assert issubclass(pacs.ChunkRejected, pacs.InputError)


@pytest.mark.parametrize(
    "kwargs, exc, words",
    [
        ({"robot": "ur5"}, pacs.InputError, ["robot", "ur5"]),
        ({"robot": 5}, pacs.ArgumentTypeError, ["robot", "5"]),
        ({"humans": "giant"}, pacs.InputError, ["humans", "giant"]),
        ({"humans": [1]}, pacs.ArgumentTypeError, ["humans[0]"]),
        ({"constraints": "dancing"}, pacs.InputError, ["constraints", "dancing"]),
        ({"config": {"safety_step": -1.0}}, pacs.InputError, ["safety_step", "-1"]),
        ({"config": {"mode": "fast"}}, pacs.InputError, ["config.mode", "fast"]),
        ({"config": {"speed": 1}}, pacs.InputError, ["config", "speed"]),
        ({"config": {"safety_step": float("nan")}}, pacs.InputError, ["config"]),
        ({"objects": [{"id": "b", "object": "rock", "contact": "ssm"}]}, pacs.InputError,
         ["objects", "rock"]),
    ],
)
def test_constructor_errors(kwargs, exc, words):
    with pytest.raises(exc) as e:
        pacs.Shield(**kwargs)
    for w in words:
        assert w in str(e.value), str(e.value)


def test_call_errors(shield, demo):
    with pytest.raises(pacs.InputError, match=r"deltas: shape \[4, 6\]"):
        shield.set_chunk(np.zeros((4, 6)), t=0.0)
    with pytest.raises(pacs.InputError, match=r"deltas\[1, 2\]: value inf"):
        d = np.zeros((3, 7))
        d[1, 2] = np.inf
        shield.set_chunk(d, t=0.0)
    with pytest.raises(pacs.ArgumentTypeError, match="deltas"):
        shield.set_chunk("left", t=0.0)
    with pytest.raises(pacs.InputError, match=r"h: 5 is outside 1..=3"):
        shield.set_chunk(np.zeros((3, 7)), t=0.0, h=5)
    with pytest.raises(pacs.ArgumentTypeError, match="t: expected a number"):
        shield.set_chunk(np.zeros((3, 7)), t="now")
    with pytest.raises(pacs.ChunkRejected, match="outside"):
        shield.set_chunk(np.full((2, 7), 3.0), t=0.0)
    with pytest.raises(pacs.InputError, match=r"positions: shape \[8, 3\]"):
        shield.measure(0.0, np.zeros((8, 3)))
    with pytest.raises(pacs.InputError, match=r"positions\[2, 1\]: value NaN"):
        p = np.zeros((9, 3))
        p[2, 1] = np.nan
        shield.measure(0.0, p)
    with pytest.raises(pacs.InputError, match="human: 3"):
        shield.measure(0.0, np.zeros((9, 3)), human=3)
    with pytest.raises(pacs.InputError, match="id: no object `ball`"):
        shield.measure_object("ball", 0.0, [0, 0, 0])
    with pytest.raises(pacs.InputError, match=r"t: value NaN"):
        shield.step(float("nan"))
    shield.step(0.0)
    with pytest.raises(pacs.InputError, match="steps follow each other by the safety step"):
        shield.step(0.0)
    with pytest.raises(pacs.InputError, match=r"q: shape \[6\]"):
        shield.start(0.0, np.zeros(6))


def test_not_started():
    s = pacs.Shield()
    with pytest.raises(pacs.NotStartedError):
        s.step(0.0)
    with pytest.raises(pacs.NotStartedError):
        s.set_chunk(np.zeros((2, 7)), t=0.0)
    with pytest.raises(pacs.NotStartedError):
        pacs.ShieldLoop(s)
    with pytest.raises(pacs.InputError, match="outside the joint position limits"):
        s.start(0.0, np.full(7, 5.0))


def test_restart_before_the_shield_time(demo):
    s = pacs.Shield()
    s.start(1.0, demo.start)
    s.step(1.0)
    with pytest.raises(pacs.InputError, match="before the shield's time"):
        s.start(0.5, demo.start)
    s.start(2.0, demo.start)
    s.step(2.0)
