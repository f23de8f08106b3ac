"""Light barrier (binary sensor): a box volume trigger latched over the physics substeps.

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
