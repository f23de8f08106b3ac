"""`from hub.participant import Participant, serve`: the participant library, kept at this name for the programs that use it (it lives in hub/bus/participant.py)."""
from hub.bus.participant import *  # noqa: F401,F403
from hub.bus.participant import __all__  # noqa: F401
