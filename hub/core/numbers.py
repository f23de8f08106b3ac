"""What counts as a number in data read back (JSON, a browser's frame): an int or float, finite, not a bool."""
from __future__ import annotations

import math


def is_number(value) -> bool:
    """An int or a finite float; a bool (an int to Python) is not one, nor NaN or an infinity."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
