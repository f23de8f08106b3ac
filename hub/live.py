"""`from hub.live import Viewer`: live viewers and operator commands, kept at this name (it lives in hub/bus/live.py)."""
from hub.bus.live import *  # noqa: F401,F403
from hub.bus.live import __all__  # noqa: F401
