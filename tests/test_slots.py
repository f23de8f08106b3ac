"""Slot types: initial values and conversion of scenario values."""
import math

import pytest

from hub.core.slots import SlotType


@pytest.mark.parametrize("kind, raw, expected", [
    (SlotType.BOOL, True, True),
    (SlotType.INT, 3, 3),
    (SlotType.REAL, 2, 2.0),
    (SlotType.VEC3, [1, 2, 3], (1.0, 2.0, 3.0)),
    (SlotType.QUAT, [0, 0, 0, 1], (0.0, 0.0, 0.0, 1.0)),
    (SlotType.STRING, "b1", "b1"),
    (SlotType.VOID, None, None),
])
def test_coerce_accepts_its_type(kind, raw, expected):
    value = kind.coerce(raw)
    assert value == expected and type(value) is type(expected)


@pytest.mark.parametrize("kind, raw", [
    (SlotType.BOOL, 1),
    (SlotType.INT, True),
    (SlotType.INT, 1.5),
    (SlotType.REAL, "1"),
    (SlotType.REAL, math.inf),
    (SlotType.VEC3, [1, 2]),
    (SlotType.QUAT, [1, 2, 3]),
    (SlotType.STRING, 5),
    (SlotType.VOID, 0),
])
def test_coerce_rejects_other_values(kind, raw):
    with pytest.raises(ValueError):
        kind.coerce(raw)


def test_initial_values_have_the_right_type_and_width():
    for kind in SlotType:
        value = kind.initial()
        if kind in (SlotType.VEC3, SlotType.QUAT):
            assert len(value) == kind.width
        assert kind.coerce(value) == value
