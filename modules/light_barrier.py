"""Light barrier (binary sensor): a box volume trigger latched over the physics substeps.

| slot             | type   | dir    | meaning                                                       |
|------------------|--------|--------|---------------------------------------------------------------|
| trigger.on_enter | void   | source | an object entered the volume in this step                     |
| trigger.on_stay  | void   | source | an object was inside at some tick of this step                |
| trigger.on_leave | void   | source | an object left the volume in this step                        |
| trigger.object   | string | source | id of the object that entered last; active with on_enter      |
| trigger.occupied | bool   | source | whether an object is inside now, every step                   |

Enter and leave events go to the event log with the exact physics tick and the object's id;
an object that enters and leaves between two communication points gives both events.
"""
from __future__ import annotations

from hub.core.module import Module

from modules.trigger import VolumeTrigger, add_volume, volume_parameters


class LightBarrier(Module):
    """A box-shaped sensing volume centred at `position`; `size` is along, across and up the belt."""

    PARAMETERS = {
        "type": "object",
        "properties": volume_parameters([0.005, 0.2, 0.02], "sensing volume"),
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"trigger": VolumeTrigger}

    @classmethod
    def build(cls, name, params, world):
        return {"trigger": VolumeTrigger(name, "trigger", world, add_volume(world, params))}
